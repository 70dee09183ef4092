// The shading points at a list of indices, gathered for reading back
// (the points the mask pool does not serve yet, where the coverage pass
// had no room to copy them all).

@group(0) @binding(ITEMS) var<storage, read> indices: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> gathered: array<SurfacePoint>;
@group(0) @binding(GATHER_SOURCE) var<storage, read> points: array<SurfacePoint>;

@compute @workgroup_size(WORKGROUP)
fn gather_points(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < params.item_count {
        var point = points[indices[id.x]];
        point.level_index = indices[id.x];
        gathered[id.x] = point;
    }
}
