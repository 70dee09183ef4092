// A shading point as the shading-point pass writes it and formula (1)
// reads it (`render/surface.rs`'s `ShadingPoint`): `hit` is 0 for a ray
// that hit nothing, whose record carries only its sample.

struct SurfacePoint {
    position: vec3<f32>,
    sample: u32,
    geometric_normal: vec3<f32>,
    depth: u32,
    shading_normal: vec3<f32>,
    front_face: u32,
    view: vec3<f32>,
    hit: u32,
    weight: vec3<f32>,
    metallic: f32,
    base_color: vec3<f32>,
    roughness: f32,
    emissive: vec3<f32>,
    specular: f32,
    transmission: f32,
    ior: f32,
    // The point's index in its level, in a copy gathered for the CPU
    // (`light_mesh_coverage.wgsl`, `gather_points.wgsl`); 0 elsewhere.
    level_index: u32,
    _pad1: u32,
}
