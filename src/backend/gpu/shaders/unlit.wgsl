// What a shading point sends that no light brought, for the beauty's
// film (`accumulate.wgsl`) and the `light` AOV's `other` layer
// (`accumulate_layers.wgsl`).

// `Environment::unlit`: emission, plus the sky times the diffuse albedo
// (`environment::diffuse_albedo`) where there is a sky.
fn unlit(point: SurfacePoint) -> vec3<f32> {
    if environment.sky == 0u {
        return point.emissive;
    }
    let albedo = scale3(point.base_color, mul(1.0 - point.transmission, 1.0 - point.metallic));
    return point.emissive + mul3(environment.ambient, albedo);
}
