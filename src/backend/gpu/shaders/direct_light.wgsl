// Formula (1) at a batch of shading points (`formula_one.wgsl`), one
// invocation each.
@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
@group(0) @binding(ANSWERS) var<storage, read_write> direct: array<DirectLight>;

@compute @workgroup_size(WORKGROUP)
fn direct_light(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let surface = points[index];
    if surface.hit == 0u {
        direct[index] = no_direct_light();
        return;
    }
    begin_terms(index);
    direct[index] = formula_one(shade_point(surface), SHADED_BY_FORMULA_ONE, no_direct_light());
}
