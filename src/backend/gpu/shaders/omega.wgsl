// Omega(i, P), the light a point light sends off a shading point towards
// the viewer, visibility aside. The arithmetic is the CPU's eight-lane
// Omega (`render/omega.rs`, `render/brdf.rs`) lane by lane, operation for
// operation: products, quotients and roots through the prelude, which
// rounds them as the CPU does where the adapter has f64, and max/min with
// the CPU lanes' choice of operand.

// A shading point with its BRDF prepared for many lights (`PointBrdf`).
struct ShadePoint {
    position: vec3<f32>,
    n_dot_v: f32,
    geometric_normal: vec3<f32>,
    alpha2: f32,
    // The BRDF's n: the shading normal.
    normal: vec3<f32>,
    view_smith: f32,
    // The BRDF's v: towards the viewer.
    view: vec3<f32>,
    metallic: f32,
    diffuse: vec3<f32>,
    specular: f32,
    base_color: vec3<f32>,
    dielectric_f0: f32,
}

// `OmegaLight`, with range_squared 0 where the light has no range.
struct Light {
    origin: vec3<f32>,
    directional: u32,
    power: vec3<f32>,
    range_squared: f32,
    axis: vec3<f32>,
    cos_outer: f32,
    cos_inner: f32,
    // Its layer of the `light` AOV (`light_layers.wgsl`).
    layer: u32,
    // Which integrator shades it, whether formula (1) tests its segment,
    // and the plan's class of the light (`ShadowSplit`, as `direct.rs`'s
    // `shading_flags` sets the contract's SHADED_BY_FORMULA_ONE,
    // SHADED_BY_LIGHT_MESH and TESTS_SEGMENT bits).
    shading: u32,
    // The lamp's radius, which sizes its penumbrae
    // (`lightmesh/penumbra.rs`).
    lamp_radius: f32,
}

// Bits 3–4 (from CLASS_SHIFT): the plan's class of the light (none,
// unshadowed, hard, soft), which its shadow rays are counted under.
fn class_of(light: Light) -> u32 {
    return light.shading >> CLASS_SHIFT & 3u;
}

@group(0) @binding(LIGHTS) var<storage, read> lights: array<Light>;

// `PointBrdf::new`: the BRDF's factors that do not depend on the light.
fn shade_point(s: SurfacePoint) -> ShadePoint {
    let n_dot_v = dot3(s.shading_normal, s.view);
    // `SurfaceMaterial::highlight_roughness`.
    let roughness = lane_max(s.roughness, 0.03);
    let alpha = mul(roughness, roughness);
    let alpha2 = mul(alpha, alpha);
    let transmitted = 1.0 - s.transmission;
    let diffuse = vec3<f32>(
        mul(div(s.base_color.x, PI), transmitted),
        mul(div(s.base_color.y, PI), transmitted),
        mul(div(s.base_color.z, PI), transmitted),
    );
    return ShadePoint(
        s.position,
        n_dot_v,
        s.geometric_normal,
        alpha2,
        s.shading_normal,
        root(mul(mul(n_dot_v, n_dot_v), 1.0 - alpha2) + alpha2),
        s.view,
        s.metallic,
        diffuse,
        s.specular,
        s.base_color,
        mul(0.04, s.specular),
    );
}

// `PointBrdf::evaluate_lanes` for one light direction; zero where the
// CPU's lane is masked off.
fn brdf(point: ShadePoint, l: vec3<f32>) -> vec3<f32> {
    if point.n_dot_v <= 0.0 {
        return vec3<f32>(0.0);
    }
    let n_dot_l = dot3(point.normal, l);
    let half = point.view + l;
    let half_squared = dot3(half, half);
    // The CPU's `1 / sqrt(h·h)` is finite and positive exactly when h·h
    // is: the test needs no infinity.
    if !(n_dot_l > 0.0 && half_squared > 0.0) {
        return vec3<f32>(0.0);
    }
    let half_recip = div(1.0, root(half_squared));
    let h = scale3(half, half_recip);
    let n_dot_h = lane_max(dot3(point.normal, h), 0.0);
    let v_dot_h = lane_min(lane_max(dot3(point.view, h), 0.0), 1.0);

    let alpha2 = point.alpha2;
    let denominator = mul(mul(n_dot_h, n_dot_h), alpha2 - 1.0) + 1.0;
    let distribution = div(alpha2, mul(mul(PI, denominator), denominator));
    let ggx_v = mul(n_dot_l, point.view_smith);
    let ggx_l = mul(point.n_dot_v, root(mul(mul(n_dot_l, n_dot_l), 1.0 - alpha2) + alpha2));
    let sum = ggx_v + ggx_l;
    let visibility = select(0.0, div(0.5, sum), sum > 0.0);
    let specular = mul(distribution, visibility);
    // v·h is in [0, 1] already: the weight's clamp changes nothing.
    let fresnel = schlick_weight(v_dot_h);

    let f0 = point.dielectric_f0;
    let dielectric_fresnel = f0 + mul(point.specular - f0, fresnel);
    var value: vec3<f32>;
    for (var c = 0u; c < 3u; c++) {
        let dielectric = mul(point.diffuse[c], 1.0 - dielectric_fresnel) + mul(specular, dielectric_fresnel);
        if point.metallic == 0.0 {
            value[c] = dielectric;
        } else {
            let base = point.base_color[c];
            let metal = mul(specular, base + mul(1.0 - base, fresnel));
            value[c] = dielectric + mul(metal - dielectric, point.metallic);
        }
    }
    return value;
}
// What `light` sends towards `point` (`LightLanes::arrival`, one lane).
struct Arrival {
    direction: vec3<f32>,
    cos_theta: f32,
    irradiance: vec3<f32>,
    // In range, inside the cone, above both horizons: the light-mesh
    // demand's reaching lights.
    reaches: bool,
}

fn arrival(point: ShadePoint, light: Light) -> Arrival {
    let directional = light.directional != 0u;
    let to_light = select(light.origin - point.position, light.origin, directional);
    let distance_squared = select(dot3(to_light, to_light), 1.0, directional);
    if !(distance_squared > 0.0) {
        return Arrival(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), false);
    }
    let ratio = select(0.0, div(distance_squared, light.range_squared), light.range_squared > 0.0);
    var window = lane_min(lane_max(1.0 - mul(ratio, ratio), 0.0), 1.0);
    window = mul(window, window);
    let length = root(distance_squared);
    let direction = vec3<f32>(div(to_light.x, length), div(to_light.y, length), div(to_light.z, length));
    let cos_angle = -dot3(direction, light.axis);
    let ramp = lane_min(lane_max(div(cos_angle - light.cos_outer, light.cos_inner - light.cos_outer), 0.0), 1.0);
    let hard_cone = select(0.0, 1.0, cos_angle > light.cos_outer);
    let cone = select(mul(ramp, ramp), hard_cone, light.cos_inner <= light.cos_outer);
    let falloff = mul(div(window, distance_squared), cone);
    let irradiance = scale3(light.power, falloff);

    let cos_theta = dot3(point.normal, direction);
    let reaches = lane_max(lane_max(irradiance.x, irradiance.y), irradiance.z) > 0.0
        && dot3(point.geometric_normal, direction) > 0.0
        && cos_theta > 0.0;
    return Arrival(direction, cos_theta, irradiance, reaches);
}

// Omega of `light` at `point` (`LightLanes::omega`, one lane); zero where
// the light brings nothing.
fn omega(point: ShadePoint, light: Light) -> vec3<f32> {
    let arriving = arrival(point, light);
    if !arriving.reaches {
        return vec3<f32>(0.0);
    }
    let irradiance = arriving.irradiance;
    let cos_theta = arriving.cos_theta;
    let reflectance = brdf(point, arriving.direction);
    let value = vec3<f32>(
        mul(mul(reflectance.x, irradiance.x), cos_theta),
        mul(mul(reflectance.y, irradiance.y), cos_theta),
        mul(mul(reflectance.z, irradiance.z), cos_theta),
    );
    if !(lane_max(lane_max(value.x, value.y), value.z) > 0.0) {
        return vec3<f32>(0.0);
    }
    return value;
}

