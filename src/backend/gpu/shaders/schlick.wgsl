// `brdf::schlick_weight`: Schlick's Fresnel weight (1 - cos)^5, the
// power taken as the CPU's `powi(5)` takes it, (c² · c²) · c.

fn schlick_weight(cos_theta: f32) -> f32 {
    let complement = 1.0 - unit_clamp(cos_theta);
    let squared = mul(complement, complement);
    return mul(mul(squared, squared), complement);
}
