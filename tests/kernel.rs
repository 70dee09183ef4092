//! Formula (2)'s kernels across a penumbra: the paper's box kernel jumps by
//! a node's share whenever a node enters or leaves the half-ball; the
//! smooth kernel's weights fall to zero at the radius, so its values
//! change no faster than its slope allows (`lightmesh::kernel`).

mod common;

use common::*;
use glam::{DMat4, DVec3, Vec3};
use lmanim::lightmesh::kernel::Kernel;
use lmanim::scene::{LightKind, SceneDesc};
use lmanim::settings::{Method, Settings};

/// Lattice step and interpolation radius of the row's light mesh.
const H: f32 = 0.05;
const KI: f32 = 2.5;
/// Pixels along the row, and the metres between neighbours on the floor.
const PIXELS: u32 = 1200;
const PIXEL_STEP: f32 = 0.0005;

/// A floor lit from 3 m straight above x = 0, and (with `blocker`) a
/// sheet at 1 m over x < 0: the hard shadow's edge is the line x = 0 on
/// the floor, which a row of pixels 0.6 m long crosses in its middle.
fn edge_scene(blocker: bool) -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 4.0)], 1, m);
    if blocker {
        let sheet = [
            Vec3::new(-2.0, 1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
            Vec3::new(0.0, 1.0, -2.0),
            Vec3::new(-2.0, 1.0, -2.0),
        ];
        add_quads(&mut scene, &[sheet], 1, m);
    }
    add_light(
        &mut scene,
        LightKind::Point,
        20.0,
        DMat4::from_translation(DVec3::new(0.0, 3.0, 0.0)),
    );
    // An orthographic view from under the sheet, 2 pixels high: 2·ymag / 2
    // metres per pixel.
    add_top_camera(&mut scene, 0.5, PIXEL_STEP);
    scene
}

/// The share of the lamp's light formula (2) gives each pixel of the row:
/// the frame with the sheet over the frame without it.
fn row(kernel: Kernel) -> (Vec<f32>, f64) {
    let mut settings = Settings {
        method: Method::Lmm1,
        ..settings(PIXELS, 2)
    };
    settings.lightmesh.h = Some(H);
    settings.lightmesh.ki = KI;
    settings.lightmesh.kernel = kernel;
    let (shadowed, stats) = render_with_stats(edge_scene(true), &settings);
    let lit = render(edge_scene(false), &settings);
    let shares = (0..PIXELS)
        .map(|x| pixel(&shadowed, x, 0).x / pixel(&lit, x, 0).x)
        .collect();
    (shares, stats.lightmesh.unwrap().mean_interp_set)
}

fn largest_step(shares: &[f32]) -> f32 {
    (shares.windows(2))
        .map(|pair| (pair[1] - pair[0]).abs())
        .fold(0.0, f32::max)
}

/// The bound, derived: with weights w(q) = (1 − q²)², q = d/r, over the
/// half-ball above a floor split by a shadow edge through the point, the
/// share U changes along the floor at the rate (weight on the edge's
/// half-disc) / (weight in the half-ball) = (π r² / 6) / (2π r³ · 8/105)
/// = 105 / (96 r), its largest, where the edge passes through the point.
/// A lattice of step h = r / 2.5 sums rather than integrates, which we
/// allow a factor of 2 for; rounding each weight to 1/4095 of its largest
/// moves a share by at most one part in 4095 · 8/35 per node weight
/// (about 0.001), twice for two neighbours.
fn smooth_bound() -> f32 {
    let r = KI * H;
    2.0 * (105.0 / (96.0 * r)) * PIXEL_STEP + 2.0 / (4095.0 * 8.0 / 35.0)
}

#[test]
fn the_smooth_kernel_crosses_a_penumbra_continuously_and_the_box_kernel_jumps() {
    let (smooth, _) = row(Kernel::Smooth);
    let (boxed, mean_set) = row(Kernel::Box);
    for (name, shares) in [("smooth", &smooth), ("box", &boxed)] {
        // The row crosses the whole transition, from umbra to full light.
        assert!(shares[0] < 0.01, "{name}: {}", shares[0]);
        assert!(shares[PIXELS as usize - 1] > 0.99, "{name}");
    }
    let bound = smooth_bound();
    assert!(
        largest_step(&smooth) <= bound,
        "smooth: a step of {} between neighbouring pixels, bound {bound}",
        largest_step(&smooth)
    );
    // The box kernel's steps are whole nodes' shares, 1/m of the set:
    // far more than the smooth kernel's slope allows at this spacing.
    let node_share = 1.0 / mean_set as f32;
    assert!(
        largest_step(&boxed) >= 0.5 * node_share,
        "box: largest step {}, a node's share {node_share}",
        largest_step(&boxed)
    );
    assert!(largest_step(&boxed) > 2.0 * bound);
}
