// The `light` AOV's film (`backend/aov.rs`'s `light_samples`): what a
// level's shading points send to each light layer of their samples, each
// point's per-layer sums (`light_layers.wgsl`) times its path throughput,
// and to `other` (the last layer of a sample) what no light brought.
// Added in point order, a sample's run of points at a time, as
// `accumulate.wgsl` adds the beauty (`sample_runs.wgsl`): the sums are the
// CPU's, bit for bit.

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
// Per sample of the band, `params.layer_count` light layers, then `other`.
@group(0) @binding(ANSWERS) var<storage, read_write> sample_layers: array<vec3<f32>>;
// Per point of the level, its terms summed per light layer.
@group(0) @binding(POINT_LAYERS) var<storage, read> point_layers: array<vec3<f32>>;

@compute @workgroup_size(WORKGROUP)
fn accumulate_layers(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if !starts_run(index) {
        return;
    }
    let sample = points[index].sample;
    let layers = params.layer_count;
    let row = sample * (layers + 1u);
    for (var i = index; i < params.item_count && points[i].sample == sample; i++) {
        let point = points[i];
        if point.hit == 0u {
            continue;
        }
        for (var layer = 0u; layer < layers; layer++) {
            let sent = mul3(point.weight, point_layers[i * layers + layer]);
            sample_layers[row + layer] = sample_layers[row + layer] + sent;
        }
        let other = mul3(point.weight, unlit(point));
        sample_layers[row + layers] = sample_layers[row + layers] + other;
    }
}
