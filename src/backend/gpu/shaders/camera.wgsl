// The camera's rays of a band of pixel samples (`backend/sampling.rs`'s
// `film_position`, `render/camera.rs`'s `FilmRays::through`): pixel centres at
// one sample per pixel, else jittered strata from a PCG32 seeded by the
// sample's index in the image, which is emulated here in 32-bit words so
// that the GPU draws the CPU's numbers.

struct Camera {
    origin: vec3<f32>,
    // 1 for a perspective camera, 0 for an orthographic one.
    perspective: u32,
    right: vec3<f32>,
    // tan(yfov / 2), as the CPU rounds it; or ymag.
    extent: f32,
    up: vec3<f32>,
    t_max: f32,
    backward: vec3<f32>,
    width: u32,
    height: u32,
    spp: u32,
    // floor(sqrt(spp)).
    strata: u32,
    first_row: u32,
    // The band's first sample in the whole image, low and high words.
    first_sample: vec2<u32>,
    // The batch's first sample in the band.
    batch_start: u32,
    _pad: u32,
}

@group(0) @binding(ITEMS) var<storage, read> cameras: array<Camera>;
@group(0) @binding(ANSWERS) var<storage, read_write> camera_paths: array<PathRay>;

// 64-bit words as (low, high).
fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let low = a.x + b.x;
    return vec2<u32>(low, a.y + b.y + select(0u, 1u, low < a.x));
}

// The full 64-bit product of two words.
fn wide_mul(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let low = a0 * b0;
    let middle = a1 * b0;
    let other = a0 * b1;
    let high = a1 * b1;
    let cross = (low >> 16u) + (middle & 0xffffu) + (other & 0xffffu);
    return vec2<u32>((cross << 16u) | (low & 0xffffu), high + (middle >> 16u) + (other >> 16u) + (cross >> 16u));
}

// The product modulo 2^64.
fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let low = wide_mul(a.x, b.x);
    return vec2<u32>(low.x, low.y + a.x * b.y + a.y * b.x);
}

fn shift_right64(a: vec2<u32>, n: u32) -> vec2<u32> {
    if n >= 32u {
        return vec2<u32>(a.y >> (n - 32u), 0u);
    }
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// PCG's XSH RR output of a state.
fn xsh_rr(state: vec2<u32>) -> u32 {
    let shifted = shift_right64(state ^ shift_right64(state, 18u), 27u).x;
    let rotation = state.y >> 27u;
    return (shifted >> rotation) | (shifted << ((32u - rotation) & 31u));
}

struct Pcg32 {
    state: vec2<u32>,
    increment: vec2<u32>,
}

const PCG_MULTIPLIER: vec2<u32> = vec2<u32>(0x4c957f2du, 0x5851f42du);

// rand_core's `seed_from_u64` for `Pcg32`: four words from its own PCG
// make the state and the (odd) increment.
fn pcg_seeded(seed: vec2<u32>) -> Pcg32 {
    var state = seed;
    var words: array<u32, 4>;
    for (var i = 0u; i < 4u; i++) {
        state = add64(mul64(state, PCG_MULTIPLIER), vec2<u32>(0x6fbe17f3u, 0xa17654e4u));
        words[i] = xsh_rr(state);
    }
    let increment = vec2<u32>(words[2] | 1u, words[3]);
    var pcg = Pcg32(add64(vec2<u32>(words[0], words[1]), increment), increment);
    pcg.state = add64(mul64(pcg.state, PCG_MULTIPLIER), increment);
    return pcg;
}

fn pcg_next(pcg: ptr<function, Pcg32>) -> u32 {
    let state = (*pcg).state;
    (*pcg).state = add64(mul64(state, PCG_MULTIPLIER), (*pcg).increment);
    return xsh_rr(state);
}

// `unit_float`: the top 24 bits of a draw, in [0, 1).
fn unit_float(pcg: ptr<function, Pcg32>) -> f32 {
    return f32(pcg_next(pcg) >> 8u) * (1.0 / 16777216.0);
}

// `film_position` of sample `s` in pixel (x, y); `index` is the sample's
// index in the whole image.
fn film_position(camera: Camera, x: u32, y: u32, s: u32, index: vec2<u32>) -> vec2<f32> {
    let corner = vec2<f32>(f32(x), f32(y));
    if camera.spp == 1u {
        return corner + vec2<f32>(0.5);
    }
    var pcg = pcg_seeded(index);
    let jx = unit_float(&pcg);
    let jy = unit_float(&pcg);
    let jitter = vec2<f32>(jx, jy);
    let strata = camera.strata;
    if s < strata * strata {
        let stratum = vec2<f32>(f32(s % strata), f32(s / strata));
        let cell = stratum + jitter;
        return corner + vec2<f32>(div(cell.x, f32(strata)), div(cell.y, f32(strata)));
    }
    return corner + jitter;
}

@compute @workgroup_size(WORKGROUP)
fn camera_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.item_count {
        return;
    }
    let camera = cameras[0];
    let index = camera.batch_start + id.x;
    let pixel = index / camera.spp;
    let s = index % camera.spp;
    let x = pixel % camera.width;
    let y = camera.first_row + pixel / camera.width;
    let film = film_position(camera, x, y, s, add64(camera.first_sample, vec2<u32>(index, 0u)));

    let width = f32(camera.width);
    let height = f32(camera.height);
    let aspect = div(width, height);
    let ndc_x = div(mul(2.0, film.x), width) - 1.0;
    let ndc_y = 1.0 - div(mul(2.0, film.y), height);
    let forward = -camera.backward;
    var ray: PathRay;
    ray.sample = index;
    ray.weight = vec3<f32>(1.0);
    ray.depth = 0u;
    ray.t_max = camera.t_max;
    let across = mul(mul(ndc_x, camera.extent), aspect);
    let along = mul(ndc_y, camera.extent);
    if camera.perspective == 1u {
        ray.origin = camera.origin;
        ray.direction = (forward + scale3(camera.right, across)) + scale3(camera.up, along);
    } else {
        ray.origin = (camera.origin + scale3(camera.right, across)) + scale3(camera.up, along);
        ray.direction = forward;
    }
    camera_paths[id.x] = ray;
}
