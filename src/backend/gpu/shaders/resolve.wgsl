// The band's pixels (`band.rs`'s `resolve`): each the mean of its
// samples' radiance (the background's where a camera ray met nothing and
// there is one), summed in sample order, with the share of samples a
// camera ray covered as alpha, or 1 behind a background. Samples per pixel: the band's samples
// over its pixels.

@group(0) @binding(ITEMS) var<storage, read> samples: array<vec4<f32>>;
@group(0) @binding(ANSWERS) var<storage, read_write> pixels: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = id.x;
    if pixel >= params.item_count {
        return;
    }
    let spp = arrayLength(&samples) / params.item_count;
    var colour = vec3<f32>(0.0);
    var covered = 0u;
    for (var s = 0u; s < spp; s++) {
        let sample = samples[pixel * spp + s];
        let hit = sample.w != 0.0;
        colour += select(sample.xyz, environment.background, environment.opaque != 0u && !hit);
        covered += select(0u, 1u, hit);
    }
    let n = f32(spp);
    let alpha = select(div(f32(covered), n), 1.0, environment.opaque != 0u);
    pixels[pixel] = vec4<f32>(div(colour.x, n), div(colour.y, n), div(colour.z, n), alpha);
}
