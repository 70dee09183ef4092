// The watertight ray/triangle test (Woop, Benthin, Wald 2013), operation
// for operation as `accel::triangle` on the CPU, with every product and
// quotient through `mul` / `div` so a compiler cannot fuse or approximate
// them differently from the CPU.

struct WatertightRay {
    origin: vec3<f32>,
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>,
    t_max: f32,
}

struct TriangleHit {
    hit: bool,
    t: f32,
    u: f32,
    v: f32,
}

fn watertight_ray(origin: vec3<f32>, direction: vec3<f32>, t_max: f32) -> WatertightRay {
    let d = abs(direction);
    // glam's max_position: the first of equal maxima.
    var kz = 0u;
    var largest = d.x;
    if d.y > largest {
        largest = d.y;
        kz = 1u;
    }
    if d.z > largest {
        kz = 2u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if direction[kz] < 0.0 {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    let dz = direction[kz];
    let shear = vec3<f32>(div(direction[kx], dz), div(direction[ky], dz), div(1.0, dz));
    return WatertightRay(origin, kx, ky, kz, shear, t_max);
}

fn permuted(ray: WatertightRay, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(p[ray.kx] - ray.origin[ray.kx], p[ray.ky] - ray.origin[ray.ky], p[ray.kz] - ray.origin[ray.kz]);
}

fn intersect_triangle(ray: WatertightRay, pa: vec3<f32>, pb: vec3<f32>, pc: vec3<f32>) -> TriangleHit {
    let miss = TriangleHit(false, 0.0, 0.0, 0.0);
    let a = permuted(ray, pa);
    let b = permuted(ray, pb);
    let c = permuted(ray, pc);
    let sx = ray.shear.x;
    let sy = ray.shear.y;
    let sz = ray.shear.z;
    let ax = a.x - mul(sx, a.z);
    let ay = a.y - mul(sy, a.z);
    let bx = b.x - mul(sx, b.z);
    let by = b.y - mul(sy, b.z);
    let cx = c.x - mul(sx, c.z);
    let cy = c.y - mul(sy, c.z);

    var u = mul(cx, by) - mul(cy, bx);
    var v = mul(ax, cy) - mul(ay, cx);
    var w = mul(bx, ay) - mul(by, ax);
    if u == 0.0 || v == 0.0 || w == 0.0 {
        u = difference_of_products(cx, by, cy, bx);
        v = difference_of_products(ax, cy, ay, cx);
        w = difference_of_products(bx, ay, by, ax);
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return miss;
    }
    let det = u + v + w;
    if det == 0.0 {
        return miss;
    }
    let t_scaled = mul(u, mul(sz, a.z)) + mul(v, mul(sz, b.z)) + mul(w, mul(sz, c.z));
    if t_scaled == 0.0 || (t_scaled < 0.0) != (det < 0.0) {
        return miss;
    }
    let rcp_det = div(1.0, det);
    let t = mul(t_scaled, rcp_det);
    if !(t > 0.0 && t < ray.t_max) {
        return miss;
    }
    return TriangleHit(true, t, mul(v, rcp_det), mul(w, rcp_det));
}

fn slot_vertex(dynamic: bool, slot: u32, corner: u32) -> vec3<f32> {
    let base = slot * 9u + corner * 3u;
    if dynamic {
        return vec3<f32>(dynamic_vertices[base], dynamic_vertices[base + 1u], dynamic_vertices[base + 2u]);
    }
    return vec3<f32>(static_vertices[base], static_vertices[base + 1u], static_vertices[base + 2u]);
}

fn intersect_slot(ray: WatertightRay, dynamic: bool, slot: u32) -> TriangleHit {
    return intersect_triangle(ray, slot_vertex(dynamic, slot, 0u), slot_vertex(dynamic, slot, 1u), slot_vertex(dynamic, slot, 2u));
}
