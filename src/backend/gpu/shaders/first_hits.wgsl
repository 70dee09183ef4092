// The camera's hits, for the `albedo`, `normal` and `depth` AOVs
// (`backend/aov.rs`'s `FirstHit`): one invocation per camera ray of a
// batch, writing its sample's record: what it hit, and how far along the
// ray, |P - O| rounded as glam's `length` rounds it; a miss is black, has
// no normal and lies infinitely far.

struct FirstHit {
    albedo: vec3<f32>,
    depth: f32,
    normal: vec3<f32>,
    covered: u32,
}

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
// Per sample of the band.
@group(0) @binding(ANSWERS) var<storage, read_write> hits: array<FirstHit>;
// The camera rays the points were made from, in the same order.
@group(0) @binding(PATHS) var<storage, read> paths: array<PathRay>;

@compute @workgroup_size(WORKGROUP)
fn first_hits(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let point = points[index];
    if point.hit == 0u {
        let infinity = bitcast<f32>(0x7f800000u);
        hits[point.sample] = FirstHit(vec3<f32>(0.0), infinity, vec3<f32>(0.0), 0u);
        return;
    }
    let to_point = point.position - paths[index].origin;
    let depth = root(dot3(to_point, to_point));
    hits[point.sample] = FirstHit(point.base_color, depth, point.shading_normal, 1u);
}
