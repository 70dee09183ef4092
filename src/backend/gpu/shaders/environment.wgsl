// The frame's background and ambient sky (`render/environment.rs`'s
// `Environment`), read by the film: `opaque` is 1 where there is a
// background, `sky` 1 where there is an ambient term.

struct Environment {
    background: vec3<f32>,
    opaque: u32,
    ambient: vec3<f32>,
    sky: u32,
}

@group(0) @binding(ENVIRONMENT) var<storage, read> environment: Environment;
