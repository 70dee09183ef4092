// The items of a ray query: render-space rays as the CPU made them.

struct Ray {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    _pad: f32,
}

@group(0) @binding(ITEMS) var<storage, read> rays: array<Ray>;
