// Formula (1) and (2) for the beauty alone: a point's terms are kept in
// its sum only, and these hooks compile to nothing, so a run without the
// `light` AOV runs the passes it ran before (`light_layers.wgsl` is the
// other side).

fn begin_terms(point: u32) {}

fn keep_term(light: Light, value: vec3<f32>) {}
