// What a level's shading points send to their pixel samples
// (`Environment::shaded_value` and `band.rs`'s `resolve`): each point's
// emission (and the ambient sky on its diffuse part) plus its direct
// light, times its path throughput, added to its sample's radiance in
// point order, a sample's run of points at a time (`sample_runs.wgsl`):
// the sums are the CPU's, bit for bit.
// Camera hits (depth 0) mark their sample covered; the shading points and
// the shadow segments are counted (integer atomics: any order gives the
// same count).

// `formula_one.wgsl`'s.
struct DirectLight {
    radiance: vec3<f32>,
    other_rays: u32,
    class_rays: vec4<u32>,
}

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
@group(0) @binding(DIRECT) var<storage, read> direct: array<DirectLight>;
// Per sample of the band: radiance, and 1 in w where a camera ray hit.
@group(0) @binding(ANSWERS) var<storage, read_write> samples: array<vec4<f32>>;
// Shading points, the segments of no light's class, then formula (1)'s
// shadow rays for each class of light.
@group(0) @binding(COUNTERS) var<storage, read_write> counters: array<atomic<u32>, FILM_COUNTERS>;

@compute @workgroup_size(WORKGROUP)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if !starts_run(index) {
        return;
    }
    let sample = points[index].sample;
    var value = samples[sample];
    var hits = 0u;
    var other_rays = 0u;
    var class_rays = vec4<u32>(0u);
    for (var i = index; i < params.item_count && points[i].sample == sample; i++) {
        let point = points[i];
        if point.hit == 0u {
            continue;
        }
        let light = direct[i];
        let shaded = unlit(point) + light.radiance;
        value = vec4<f32>(value.xyz + mul3(point.weight, shaded), select(value.w, 1.0, point.depth == 0u));
        hits += 1u;
        other_rays += light.other_rays;
        class_rays += light.class_rays;
    }
    samples[sample] = value;
    atomicAdd(&counters[COUNTER_SHADING_POINTS], hits);
    atomicAdd(&counters[COUNTER_OTHER_RAYS], other_rays);
    for (var shadow_class = 0u; shadow_class < SHADOW_CLASSES; shadow_class++) {
        atomicAdd(&counters[COUNTER_CLASS_RAYS + shadow_class], class_rays[shadow_class]);
    }
}
