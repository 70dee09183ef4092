// Shading points from closest hits (`render/surface.rs`,
// `render/material.rs`): the hit's position from its barycentrics on the
// placed triangle, the geometric normal as the ray tracer reports it, the
// interpolated shading normal and texture coordinates, and the material
// with its base colour and emissive textures sampled there. Each step
// rounds as the CPU's does (see `vector.wgsl`), so a point made here is
// the CPU's point, bit for bit, where the adapter has f64.

// A mesh's arrays, as word offsets into `mesh_words` and element counts.
// Normals and texture coordinates may be absent (count 0); a triangle
// past `material_count` takes material 0.
struct MeshRecord {
    indices: u32,
    triangle_count: u32,
    positions: u32,
    vertex_count: u32,
    normals: u32,
    normal_count: u32,
    uvs: u32,
    uv_count: u32,
    materials: u32,
    material_count: u32,
    _pad0: u32,
    _pad1: u32,
}

// Wrap modes: 0 repeat, 1 mirrored repeat, 2 clamp to edge.
struct TextureRecord {
    texels: u32,
    width: u32,
    height: u32,
    wrap_s: u32,
    wrap_t: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// An object as the frame places it: its affine map into render space by
// columns (translation last), the inverse transpose for shading normals,
// the cofactor map the ray tracer turns an instance's normals with, and
// its deformed vertices in `deformed` (NONE where it does not deform).
struct ObjectRecord {
    to_render: array<vec4<f32>, 4>,
    normal_to_render: array<vec4<f32>, 3>,
    cofactor: array<vec4<f32>, 3>,
    mesh: u32,
    deformed_positions: u32,
    deformed_normals: u32,
    deformed_normal_count: u32,
}

// A material's factors and texture indices (NONE for no texture); the
// last record is the default material, for indices past the others.
struct MaterialRecord {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    base_color_texture: u32,
    metallic: f32,
    roughness: f32,
    specular: f32,
    transmission: f32,
    ior: f32,
    emissive_texture: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(ITEMS) var<storage, read> paths: array<PathRay>;
@group(0) @binding(HITS) var<storage, read> hits: array<HitRecord>;
@group(0) @binding(MESHES) var<storage, read> meshes: array<MeshRecord>;
// Triangle indices and material indices as words, positions, normals and
// texture coordinates as the bits of their floats.
@group(0) @binding(MESH_WORDS) var<storage, read> mesh_words: array<u32>;
@group(0) @binding(TEXTURES) var<storage, read> textures: array<TextureRecord>;
@group(0) @binding(TEXELS) var<storage, read> texels: array<vec4<f32>>;
@group(0) @binding(OBJECTS) var<storage, read> objects: array<ObjectRecord>;
@group(0) @binding(MATERIALS) var<storage, read> materials: array<MaterialRecord>;
@group(0) @binding(DEFORMED) var<storage, read> deformed: array<f32>;
@group(0) @binding(ANSWERS) var<storage, read_write> points: array<SurfacePoint>;

fn word_vec3(offset: u32, index: u32) -> vec3<f32> {
    let base = offset + 3u * index;
    return bitcast<vec3<f32>>(vec3<u32>(mesh_words[base], mesh_words[base + 1u], mesh_words[base + 2u]));
}

fn deformed_vec3(offset: u32, index: u32) -> vec3<f32> {
    let base = offset + 3u * index;
    return vec3<f32>(deformed[base], deformed[base + 1u], deformed[base + 2u]);
}

// Vertex `index`'s position or normal: from the frame's deformed mesh at
// `deformed_offset` where the object deforms (NONE where it does not),
// else from the mesh's words at `mesh_offset`.
fn vertex_vec3(deformed_offset: u32, mesh_offset: u32, index: u32) -> vec3<f32> {
    if deformed_offset == NONE {
        return word_vec3(mesh_offset, index);
    }
    return deformed_vec3(deformed_offset, index);
}

// `Affine3A::transform_point3`.
fn to_render(object: ObjectRecord, p: vec3<f32>) -> vec3<f32> {
    let m = object.to_render;
    return map3(m[0].xyz, m[1].xyz, m[2].xyz, p) + m[3].xyz;
}

// `w a + u b + v c`, as `render/surface.rs` weights the corners.
fn interpolate3(w: f32, u: f32, v: f32, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    return (scale3(a, w) + scale3(b, u)) + scale3(c, v);
}

// `i` wrapped into 0..n by `mode`, as `material.rs`'s `wrap` (which works
// in i64: texel coordinates past ±2^30 are clamped there first, where
// the CPU would wrap them).
fn wrap(i: i32, n: i32, mode: u32) -> i32 {
    if mode == 2u {
        return clamp(i, 0, n - 1);
    }
    if mode == 0u {
        return ((i % n) + n) % n;
    }
    let period = ((i % (2 * n)) + 2 * n) % (2 * n);
    return select(2 * n - 1 - period, period, period < n);
}

fn lerp4(a: vec4<f32>, b: vec4<f32>, s: f32) -> vec4<f32> {
    let r = 1.0 - s;
    return vec4<f32>(mul(a.x, r), mul(a.y, r), mul(a.z, r), mul(a.w, r))
        + vec4<f32>(mul(b.x, s), mul(b.y, s), mul(b.z, s), mul(b.w, s));
}

fn texel(texture: TextureRecord, x: i32, y: i32) -> vec4<f32> {
    let width = i32(texture.width);
    let height = i32(texture.height);
    let column = wrap(x, width, texture.wrap_s);
    let row = wrap(y, height, texture.wrap_t);
    return texels[texture.texels + u32(row * width + column)];
}

// `sample_bilinear`: texel centres at half-integer coordinates; white
// where there is no texture, no texel or no finite coordinate.
fn sample(index: u32, uv: vec2<f32>) -> vec4<f32> {
    if index >= arrayLength(&textures) {
        return vec4<f32>(1.0);
    }
    let texture = textures[index];
    if texture.width == 0u || texture.height == 0u || !is_finite(uv.x) || !is_finite(uv.y) {
        return vec4<f32>(1.0);
    }
    let x = mul(uv.x, f32(texture.width)) - 0.5;
    let y = mul(uv.y, f32(texture.height)) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let limit = 1073741824.0; // 2^30
    let ix = i32(clamp(x0, -limit, limit));
    let iy = i32(clamp(y0, -limit, limit));
    let top = lerp4(texel(texture, ix, iy), texel(texture, ix + 1, iy), fx);
    let bottom = lerp4(texel(texture, ix, iy + 1), texel(texture, ix + 1, iy + 1), fx);
    return lerp4(top, bottom, fy);
}

// The surface point of a ray's closest hit: `ShadingPoint::from_hit`.
fn surface_point(ray: PathRay, hit: HitRecord) -> SurfacePoint {
    var point: SurfacePoint;
    point.sample = ray.sample;
    point.weight = ray.weight;
    point.depth = ray.depth;
    point.hit = 1u;
    let object = objects[hit.object];
    let mesh = meshes[object.mesh];
    let corners = mesh.indices + 3u * hit.triangle;
    let a = mesh_words[corners];
    let b = mesh_words[corners + 1u];
    let c = mesh_words[corners + 2u];
    let u = hit.u;
    let v = hit.v;
    let w = 1.0 - u - v;

    let pa = vertex_vec3(object.deformed_positions, mesh.positions, a);
    let pb = vertex_vec3(object.deformed_positions, mesh.positions, b);
    let pc = vertex_vec3(object.deformed_positions, mesh.positions, c);
    let ra = to_render(object, pa);
    let rb = to_render(object, pb);
    let rc = to_render(object, pc);
    point.position = interpolate3(w, u, v, ra, rb, rc);

    // The ray tracer's normal: from the render-space corners of a static
    // triangle, from the object-space ones of an instance's, turned by
    // the cofactor map.
    var hit_normal: vec3<f32>;
    if hit.mesh == 0u {
        hit_normal = triangle_normal(ra, rb, rc);
    } else {
        let m = object.cofactor;
        hit_normal = normalize3(map3(m[0].xyz, m[1].xyz, m[2].xyz, triangle_normal(pa, pb, pc)));
    }
    let towards_viewer = -normalize3(ray.direction);
    let front_face = dot3(hit_normal, towards_viewer) >= 0.0;
    let geometric_normal = select(-hit_normal, hit_normal, front_face);
    point.front_face = select(0u, 1u, front_face);
    point.geometric_normal = geometric_normal;
    point.view = towards_viewer;

    var normal_count = mesh.normal_count;
    if object.deformed_positions != NONE {
        normal_count = object.deformed_normal_count;
    }
    point.shading_normal = geometric_normal;
    if a < normal_count && b < normal_count && c < normal_count {
        let na = vertex_vec3(object.deformed_normals, mesh.normals, a);
        let nb = vertex_vec3(object.deformed_normals, mesh.normals, b);
        let nc = vertex_vec3(object.deformed_normals, mesh.normals, c);
        let m = object.normal_to_render;
        let n = normalize_or_zero3(map3(m[0].xyz, m[1].xyz, m[2].xyz, interpolate3(w, u, v, na, nb, nc)));
        if dot3(n, geometric_normal) > 0.0 {
            point.shading_normal = n;
        } else if any(n != vec3<f32>(0.0)) {
            point.shading_normal = -n;
        }
    }

    var uv = vec2<f32>(0.0);
    if a < mesh.uv_count && b < mesh.uv_count && c < mesh.uv_count {
        let ta = bitcast<vec2<f32>>(vec2<u32>(mesh_words[mesh.uvs + 2u * a], mesh_words[mesh.uvs + 2u * a + 1u]));
        let tb = bitcast<vec2<f32>>(vec2<u32>(mesh_words[mesh.uvs + 2u * b], mesh_words[mesh.uvs + 2u * b + 1u]));
        let tc = bitcast<vec2<f32>>(vec2<u32>(mesh_words[mesh.uvs + 2u * c], mesh_words[mesh.uvs + 2u * c + 1u]));
        uv = (vec2<f32>(mul(ta.x, w), mul(ta.y, w)) + vec2<f32>(mul(tb.x, u), mul(tb.y, u)))
            + vec2<f32>(mul(tc.x, v), mul(tc.y, v));
    }
    var material_index = 0u;
    if hit.triangle < mesh.material_count {
        material_index = mesh_words[mesh.materials + hit.triangle];
    }
    let material = materials[min(material_index, arrayLength(&materials) - 1u)];
    let base_texel = sample(material.base_color_texture, uv);
    point.base_color = mul3(material.base_color.xyz, base_texel.xyz);
    point.metallic = unit_clamp(material.metallic);
    point.roughness = unit_clamp(material.roughness);
    point.specular = unit_clamp(material.specular);
    point.transmission = unit_clamp(material.transmission);
    point.ior = material.ior;
    point.emissive = mul3(material.emissive, sample(material.emissive_texture, uv).xyz);
    return point;
}

@compute @workgroup_size(WORKGROUP)
fn surface(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let hit = hits[index];
    if hit.mesh == NO_MESH {
        var miss: SurfacePoint;
        miss.sample = paths[index].sample;
        miss.hit = 0u;
        points[index] = miss;
        return;
    }
    points[index] = surface_point(paths[index], hit);
}
