//! How wide should the light mesh be? LMM's penumbra against the physical
//! one (the Monte Carlo spherical lamp, `--method area`) for a lamp of
//! radius R above a square occluder halfway to the floor, as the lattice step
//! h varies in units of R / kI. The error is the RMS difference of the
//! floor's radiance over the penumbra region, relative to the lit level.
//!
//! `cargo bench --bench penumbra` prints a Markdown table; the default-h rule
//! in `src/lightmesh/spacing.rs` is chosen from it (BENCHMARKS.md).

use glam::{Quat, Vec2, Vec3};
use lmanim::backend::Backend;
use lmanim::output::Image;
use lmanim::scene::{Camera, Light, LightKind, Material, Projection};
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};
use lmanim::stats::FrameStats;
use lmanim_authoring::{shapes, GltfBuilder, NodeDesc, Primitive};

const LAMP_HEIGHT: f32 = 2.0;
const OCCLUDER_HEIGHT: f32 = 1.0;
const KI: f32 = 2.5;

fn scene(radius: f32) -> GltfBuilder {
    let mut b = GltfBuilder::new();
    let grey = b
        .add_material(&Material {
            base_color: Vec3::splat(0.5).extend(1.0),
            metallic: 0.0,
            specular: 0.0,
            ..Material::default()
        })
        .expect("material");
    let floor = b
        .add_geometry(&shapes::plane(Vec2::splat(4.0)))
        .expect("floor");
    let slab = b
        .add_geometry(&shapes::cuboid(Vec3::new(0.25, 0.02, 0.25)))
        .expect("slab");
    for (name, geometry, height) in [("Floor", floor, 0.0), ("Occluder", slab, OCCLUDER_HEIGHT)] {
        let mesh = b
            .add_mesh(
                name,
                &[Primitive {
                    geometry,
                    material: Some(grey),
                }],
            )
            .expect("mesh");
        b.add_node(NodeDesc {
            translation: Vec3::new(0.0, height, 0.0),
            mesh: Some(mesh),
            ..NodeDesc::named(name)
        })
        .expect("node");
    }
    let lamp = b
        .add_light(&Light {
            name: Some("Lamp".into()),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 20.0,
            range: None,
            radius: Some(radius),
            group: None,
        })
        .expect("light");
    b.add_node(NodeDesc {
        translation: Vec3::new(0.0, LAMP_HEIGHT, 0.0),
        light: Some(lamp),
        ..NodeDesc::named("Lamp")
    })
    .expect("lamp node");
    let camera = b
        .add_camera(&Camera {
            name: Some("top".into()),
            projection: Projection::Orthographic {
                xmag: 1.0,
                ymag: 1.0,
                znear: 0.0,
                zfar: 10.0,
            },
        })
        .expect("camera");
    b.add_node(NodeDesc {
        translation: Vec3::new(0.0, 0.5, 0.0),
        rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        camera: Some(camera),
        ..NodeDesc::named("top")
    })
    .expect("camera node");
    b
}

fn render(path: &std::path::Path, settings: &Settings, backend: &mut Backend) -> (Image, f64) {
    let mut sequence = Sequence::load(path).expect("scene loads");
    let placed = sequence.place(settings).expect("camera");
    let mut stats = FrameStats::default();
    let start = std::time::Instant::now();
    let image = sequence
        .render(backend, &placed, settings, &mut stats)
        .expect("renders");
    (image, start.elapsed().as_secs_f64())
}

fn main() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, None).expect("threads");
    let size = 160;
    println!("| R (m) | method | h·kI / R | h (m) | RMS error / lit | seconds |");
    println!("|---|---|---|---|---|---|");
    for radius in [0.1f32, 0.2] {
        let path = dir.path().join(format!("penumbra{radius}.glb"));
        scene(radius).write_glb(&path).expect("scene written");
        let base = Settings {
            width: size,
            height: size,
            ..Settings::default()
        };
        let (reference, reference_seconds) = render(
            &path,
            &Settings {
                method: Method::Area,
                spp: 1024,
                ..base.clone()
            },
            &mut backend,
        );
        if let Some(dir) = std::env::var_os("LMANIM_BENCH_DUMP") {
            let name = format!("area-r{radius}.png");
            lmanim::output::write_png_preview(
                &std::path::Path::new(&dir).join(name),
                &reference,
                0.0,
            )
            .expect("png");
        }
        let lit = reference.pixels.iter().map(|p| p.x).fold(0.0, f32::max);
        // The penumbra region: pixels the reference shows partly lit.
        let region: Vec<usize> = (0..reference.pixels.len())
            .filter(|&i| (0.02..0.98).contains(&(reference.pixels[i].x / lit)))
            .collect();
        let error = |image: &Image| {
            let sum: f64 = region
                .iter()
                .map(|&i| ((image.pixels[i].x - reference.pixels[i].x) / lit).powi(2) as f64)
                .sum();
            (sum / region.len().max(1) as f64).sqrt()
        };
        println!("| {radius} | area 1024 spp | — | — | 0 (reference) | {reference_seconds:.2} |");
        let (whitted, seconds) = render(&path, &base, &mut backend);
        println!(
            "| {radius} | whitted | — | — | {:.4} | {seconds:.2} |",
            error(&whitted)
        );
        for spp in [4, 16] {
            let (area, seconds) = render(
                &path,
                &Settings {
                    method: Method::Area,
                    spp,
                    ..base.clone()
                },
                &mut backend,
            );
            println!(
                "| {radius} | area {spp} spp | — | — | {:.4} | {seconds:.2} |",
                error(&area)
            );
        }
        for method in [Method::Lmm, Method::Lmm1] {
            for scale in [0.5f32, 1.0, 1.5, 2.0, 3.0] {
                let h = scale * radius / KI;
                let mut settings = Settings {
                    method,
                    ..base.clone()
                };
                settings.lightmesh.h = Some(h);
                settings.lightmesh.ki = KI;
                let (image, seconds) = render(&path, &settings, &mut backend);
                if let Some(dir) = std::env::var_os("LMANIM_BENCH_DUMP") {
                    let name = format!("{method}-r{radius}-s{scale}.png");
                    lmanim::output::write_png_preview(
                        &std::path::Path::new(&dir).join(name),
                        &image,
                        0.0,
                    )
                    .expect("png");
                }
                println!(
                    "| {radius} | {method} | {scale} | {h:.3} | {:.4} | {seconds:.2} |",
                    error(&image)
                );
            }
        }
    }
}
