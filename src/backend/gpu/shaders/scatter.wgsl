// The Whitted recursion's rays (`render/scatter.rs`): each shading point's
// mirror-reflected and refracted rays with the throughput they carry, in
// two slots per point (reflection first), and how many it spawned. The
// compaction passes then pack them in point order, as the CPU lists them.

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
@group(0) @binding(ANSWERS) var<storage, read_write> slots: array<PathRay>;
@group(0) @binding(SECOND_OUTPUT) var<storage, read_write> counts: array<u32>;

// Below it a surface is a mirror (`material.rs`'s `MIRROR_ROUGHNESS`).
const MIRROR_ROUGHNESS: f32 = 0.1;

// `brdf::mirror_reflectance`.
fn mirror_reflectance(point: SurfacePoint, cos_theta: f32) -> vec3<f32> {
    let fresnel = schlick_weight(cos_theta);
    let f0 = mul(0.04, point.specular);
    let dielectric = f0 + mul(point.specular - f0, fresnel);
    let base = point.base_color;
    let metal = base + scale3(vec3<f32>(1.0) - base, fresnel);
    // `Vec3::lerp`: a (1 - s) + b s.
    return scale3(vec3<f32>(dielectric), 1.0 - point.metallic) + scale3(metal, point.metallic);
}

// `dielectric_fresnel`: Schlick's, on the transmitted side's cosine when
// leaving the denser medium.
fn dielectric_fresnel(cos_i: f32, eta: f32) -> f32 {
    let q = div(1.0 - eta, 1.0 + eta);
    let f0 = mul(q, q);
    var cos = cos_i;
    if eta > 1.0 {
        let sin2_t = mul(mul(eta, eta), 1.0 - mul(cos_i, cos_i));
        if sin2_t >= 1.0 {
            return 1.0;
        }
        cos = root(1.0 - sin2_t);
    }
    return f0 + mul(1.0 - f0, schlick_weight(cos));
}

fn path_ray(origin: vec3<f32>, direction: vec3<f32>, point: SurfacePoint, weight: vec3<f32>) -> PathRay {
    let infinity = bitcast<f32>(0x7f800000u);
    return PathRay(origin, infinity, direction, point.sample, weight, point.depth + 1u);
}

@compute @workgroup_size(WORKGROUP)
fn scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let point = points[index];
    var count = 0u;
    if point.hit == 0u {
        counts[index] = 0u;
        return;
    }
    let n = point.shading_normal;
    let v = point.view;
    let cos_view = unit_clamp(dot3(n, v));
    let mirror = scale3(n, mul(2.0, dot3(n, v))) - v;
    let reflects = point.roughness < MIRROR_ROUGHNESS && (point.metallic > 0.0 || point.specular > 0.0);
    let transmits = point.transmission > 0.0 && point.metallic < 1.0;

    var reflection_weight = vec3<f32>(0.0);
    if reflects {
        reflection_weight = mirror_reflectance(point, cos_view);
    }
    var refraction: PathRay;
    var refracts = false;
    if transmits {
        let eta = select(point.ior, div(1.0, point.ior), point.front_face != 0u);
        let fresnel = dielectric_fresnel(cos_view, eta);
        let transmitted = scale3(point.base_color, mul(point.transmission, 1.0 - point.metallic));
        // `refract`: None on total internal reflection.
        let cos_i = dot3(n, v);
        let sin2_t = mul(mul(eta, eta), lane_max(1.0 - mul(cos_i, cos_i), 0.0));
        if sin2_t >= 1.0 {
            reflection_weight += transmitted;
        } else {
            let cos_t = root(1.0 - sin2_t);
            let direction = normalize3(scale3(-v, eta) + scale3(n, mul(eta, cos_i) - cos_t));
            let origin = offset_ray_origin(point.position, -point.geometric_normal);
            let weight = scale3(mul3(point.weight, transmitted), 1.0 - fresnel);
            refraction = path_ray(origin, direction, point, weight);
            refracts = true;
            if !reflects {
                reflection_weight += scale3(transmitted, fresnel);
            }
        }
    }
    let base = 2u * index;
    if reflection_weight.x > 0.0 || reflection_weight.y > 0.0 || reflection_weight.z > 0.0 {
        let origin = offset_ray_origin(point.position, point.geometric_normal);
        slots[base] = path_ray(origin, mirror, point, mul3(point.weight, reflection_weight));
        count = 1u;
    }
    if refracts {
        slots[base + count] = refraction;
        count += 1u;
    }
    counts[index] = count;
}
