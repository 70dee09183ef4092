// The rays of camera paths (the items of the closest-hit and shading-point
// passes): a ray as the camera or the Whitted recursion made it, the
// pixel sample its hit shades, the path's throughput and its Whitted
// depth. And the closest hit of each, as the closest-hit pass writes it
// and the shading-point pass reads it.

struct PathRay {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    sample: u32,
    weight: vec3<f32>,
    depth: u32,
}

struct HitRecord {
    t: f32,
    u: f32,
    v: f32,
    // 0 for the static mesh, 1 + i for instance i, NO_MESH for none.
    mesh: u32,
    slot: u32,
    object: u32,
    triangle: u32,
    _pad: u32,
}
