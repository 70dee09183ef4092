// Formula (1) and (2) for the `light` AOV (`backend/aov.rs`): each
// point's terms summed per light layer (the light's `layer`), in light
// order as the CPU sums its logged terms, into the point's row of
// `point_layers`, which the film weights by the point's path throughput
// (`accumulate_layers.wgsl`). Rows start zeroed (a fresh buffer per
// level), and only the invocation of their point writes them.

// Per point of the pass, `params.layer_count` sums.
@group(0) @binding(POINT_LAYERS) var<storage, read_write> point_layers: array<vec3<f32>>;

// Where the current point's row starts.
var<private> point_row: u32;

fn begin_terms(point: u32) {
    point_row = point * params.layer_count;
}

fn keep_term(light: Light, value: vec3<f32>) {
    let at = point_row + light.layer;
    point_layers[at] = point_layers[at] + value;
}
