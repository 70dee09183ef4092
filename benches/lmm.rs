//! The paper's cost model (section 3) made concrete: Whitted, LMM1 and LMM
//! on the generated city block for nL = 1, 4, 16, 64 street lamps at 480p
//! and 1080p, one cold frame each, with N_LM against N_pix.
//!
//! Then LMM1 at 64 lamps on lattices 1.5, 2 and 3 times coarser than the
//! default h: what the speed-up costs in penumbra accuracy is in the
//! penumbra bench's table at the same ratios.
//!
//! Then frames that reuse masks: the camera flying over the still
//! 64-lamp city (its "flythrough"), frame 0 cold and frames 1–3 in the
//! same sequence, Whitted against LMM1 (issue 34's steady-frame figure).
//!
//! Then the paper's table of step-3 tests per point, on the city's walls and
//! corners, for kI = 2.1, 2.5, 3.0.
//!
//! `cargo bench --bench lmm` prints Markdown tables (BENCHMARKS.md keeps
//! them). `LMANIM_BENCH_QUICK=1` runs 480p only; `LMANIM_BENCH_LAMPS=64`
//! and `LMANIM_BENCH_HEIGHT=1080` run one lamp count and one size (and
//! skip the kI table), for profiling one case; `LMANIM_BENCH_HEIGHT=2160`
//! runs 3840×2160, the large image where the paper puts the method's
//! advantage (issue 34's cold-frame figure), which the full run leaves
//! out for its time. `LMANIM_BENCH_BACKEND=gpu`
//! runs the matrix on the GPU backend (the adapter is printed: a software
//! one's timings say nothing of a GPU's); with it, `LMANIM_BENCH_SHAFTS=skip`
//! makes the fill trace every missing bit instead of settling groups by
//! shafts first (same bits; `lightmesh::segments`). `LMANIM_BENCH_SCENES=DIR` keeps
//! the generated cities in DIR, for timing one frame with `lmanim` itself
//! (`perf stat` counts its CPU time, which a busy machine disturbs less
//! than the wall clock).

use std::path::Path;
use std::time::Instant;

use lmanim::backend::Backend;
use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::lightmesh::segments::Shafts;
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};
use lmanim::stats::FrameStats;
use lmanim_authoring::city::{city_block, CityParams};

fn main() {
    let quick = std::env::var_os("LMANIM_BENCH_QUICK").is_some();
    let only_height: Option<u32> = std::env::var("LMANIM_BENCH_HEIGHT").ok().map(|height| {
        height
            .parse()
            .expect("LMANIM_BENCH_HEIGHT is 480, 1080 or 2160")
    });
    let sizes: Vec<(u32, u32)> = [(854, 480), (1920, 1080), (3840, 2160)]
        .into_iter()
        .filter(|&(_, height)| match only_height {
            Some(only) => height == only,
            None => height == 480 || (!quick && height == 1080),
        })
        .collect();
    let dir = tempfile::tempdir().expect("temporary directory");
    let kept = std::env::var_os("LMANIM_BENCH_SCENES").map(std::path::PathBuf::from);
    let dir = kept.as_deref().unwrap_or(dir.path());
    let kind = match std::env::var("LMANIM_BENCH_BACKEND").as_deref() {
        Ok("gpu") => lmanim::settings::BackendKind::Gpu,
        Ok("cpu") | Err(_) => lmanim::settings::BackendKind::Cpu,
        Ok(other) => panic!("LMANIM_BENCH_BACKEND is cpu or gpu, not {other}"),
    };
    let mut backend = lmanim::backend::Backend::new(kind, None).expect("backend");
    match std::env::var("LMANIM_BENCH_SHAFTS").as_deref() {
        Ok("test") | Err(_) => {}
        Ok("skip") => backend.set_fill_shafts(Shafts::Skip),
        Ok(other) => panic!("LMANIM_BENCH_SHAFTS is test or skip, not {other}"),
    }
    println!("threads: {}", backend.threads());
    if let Some(adapter) = backend.adapter() {
        println!("adapter: {adapter}");
    }
    let mut stage_rows = Vec::new();
    // The 64-lamp LMM1 case at the largest size, for the lattice sweep.
    let mut coarser = None;
    println!("| nL | size | method | seconds | vs Whitted | N_pix (points) | N_LM | bits computed | mean p2n tests | shadow rays |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let only_lamps: Option<u32> = std::env::var("LMANIM_BENCH_LAMPS")
        .ok()
        .map(|lamps| lamps.parse().expect("LMANIM_BENCH_LAMPS is a number"));
    let lamp_counts: Vec<u32> = match only_lamps {
        Some(lamps) => vec![lamps],
        None => vec![1, 4, 16, 64],
    };
    for lamps in lamp_counts {
        let path = dir.join(format!("city{lamps}.glb"));
        city_block(&CityParams {
            lamps,
            ..CityParams::default()
        })
        .and_then(|city| city.write_glb(&path))
        .expect("city scene");
        for &(width, height) in &sizes {
            let mut whitted_seconds = 0.0;
            // LMM1 with the default penumbrae (sized by their blockers,
            // the wide set asked too), with `blocker` alone and with the
            // paper's fixed radius: what the default costs.
            let variants = [
                (Method::Whitted, Penumbra::default()),
                (Method::Lmm1, Penumbra::default()),
                (Method::Lmm1, Penumbra::Blocker),
                (Method::Lmm1, Penumbra::Fixed),
                (Method::Lmm, Penumbra::default()),
            ];
            for (method, penumbra) in variants {
                let mut settings = Settings {
                    width,
                    height,
                    method,
                    ..Settings::default()
                };
                settings.lightmesh.penumbra = penumbra;
                let label = match penumbra == Penumbra::default() {
                    true => method.to_string(),
                    false => format!("{method}, {penumbra:?}").to_lowercase(),
                };
                let (seconds, stats) = render_cold(&mut backend, &path, &settings);
                if method == Method::Whitted {
                    whitted_seconds = seconds;
                }
                let mesh = stats.lightmesh.unwrap_or_default();
                if (lamps, method, penumbra) == (64, Method::Lmm1, Penumbra::default()) {
                    coarser = Some((path.clone(), settings.clone(), whitted_seconds, mesh.h));
                }
                println!(
                    "| {lamps} | {height}p | {label} | {seconds:.2} | {:.1}× | {} | {} | {} | {:.1} | {} |",
                    whitted_seconds / seconds,
                    stats.shading_points,
                    mesh.nodes_computed,
                    mesh.bits_computed,
                    mesh.mean_p2n_tests,
                    stats.rays.shadow
                );
                if lamps == 64 {
                    let stages = stage_seconds(&stats);
                    let fill = match stats.lightmesh {
                        Some(mesh) => format!(
                            "{} shafts, {} segments ({} remembered), {} hidden groups; \
                             {} points settled by agreement; \
                             blocker rays {} ({} level segments remembered)",
                            mesh.fill_shafts,
                            mesh.fill_segments,
                            mesh.fill_remembered,
                            mesh.fill_hidden_groups,
                            mesh.points_settled,
                            mesh.blocker_rays,
                            mesh.blocker_rays_remembered
                        ),
                        None => "—".to_string(),
                    };
                    stage_rows.push(format!("| {height}p | {label} | {stages} | {fill} |"));
                }
            }
        }
    }

    println!();
    println!("Stage seconds at 64 lamps:");
    println!();
    println!("| size | method | stages | fill and blocker work |");
    println!("|---|---|---|---|");
    for row in stage_rows {
        println!("{row}");
    }

    if let Some((path, settings, whitted_seconds, default_h)) = coarser {
        println!();
        println!(
            "LMM1 at 64 lamps, {}p, on coarser lattices (Whitted: {whitted_seconds:.2} s):",
            settings.height
        );
        println!();
        println!("| h / default h | h (m) | seconds | vs Whitted | N_LM | bits computed |");
        println!("|---|---|---|---|---|---|");
        for scale in [1.5f32, 2.0, 3.0] {
            let mut settings = settings.clone();
            settings.lightmesh.h = Some(default_h * scale);
            let (seconds, stats) = render_cold(&mut backend, &path, &settings);
            let mesh = stats.lightmesh.unwrap_or_default();
            println!(
                "| {scale} | {:.3} | {seconds:.2} | {:.1}× | {} | {} |",
                mesh.h,
                whitted_seconds / seconds,
                mesh.nodes_computed,
                mesh.bits_computed
            );
        }
    }

    if only_lamps.is_none_or(|lamps| lamps == 64) {
        let path = dir.join("city64-flying.glb");
        city_block(&CityParams {
            lamps: 64,
            flythrough: true,
            ..CityParams::default()
        })
        .and_then(|city| city.write_glb(&path))
        .expect("city scene");
        println!();
        println!("Frames that reuse masks: the camera flying over the still 64-lamp city:");
        println!();
        println!("| size | method | frame 0 (cold) | frames 1–3 (each) | steady vs Whitted | frame 3's stages |");
        println!("|---|---|---|---|---|---|");
        for &(width, height) in &sizes {
            let mut whitted_steady = 0.0;
            for method in [Method::Whitted, Method::Lmm1] {
                let settings = Settings {
                    width,
                    height,
                    method,
                    camera: Some("flythrough".into()),
                    ..Settings::default()
                };
                let (seconds, last) = render_flying(&mut backend, &path, &settings, 4);
                let steady = &seconds[1..];
                let mean = steady.iter().sum::<f64>() / steady.len() as f64;
                if method == Method::Whitted {
                    whitted_steady = mean;
                }
                let each: Vec<String> = steady.iter().map(|s| format!("{s:.2}")).collect();
                println!(
                    "| {height}p | {method} | {:.2} | {} | {:.2}× | {} |",
                    seconds[0],
                    each.join(", "),
                    whitted_steady / mean,
                    stage_seconds(&last)
                );
            }
        }
    }

    if only_lamps.is_some() {
        return;
    }
    println!();
    println!("| kI | mean candidates (steps 1-2) | mean p2n tests (step 3) | mean interpolation set | paper's mean tests | half-ball volume |");
    println!("|---|---|---|---|---|---|");
    let path = dir.join("city16.glb");
    for (ki, paper) in [(2.1f32, 16.5), (2.5, 30.4), (3.0, 53.4)] {
        let mut settings = Settings {
            width: 854,
            height: 480,
            method: Method::Lmm,
            ..Settings::default()
        };
        settings.lightmesh.ki = ki;
        let (_, stats) = render_cold(&mut backend, &path, &settings);
        let mesh = stats.lightmesh.unwrap_or_default();
        let volume = 2.0 / 3.0 * std::f64::consts::PI * f64::from(ki).powi(3);
        println!(
            "| {ki} | {:.1} | {:.1} | {:.1} | {paper} | {volume:.1} |",
            mesh.mean_candidates, mesh.mean_p2n_tests, mesh.mean_interp_set
        );
    }
}

/// The first `frames` frames of the scene at `path` at 24 fps, in one
/// sequence (the first cold, the others reusing its masks): each one's
/// seconds, and the last one's statistics.
fn render_flying(
    backend: &mut Backend,
    path: &Path,
    settings: &Settings,
    frames: u32,
) -> (Vec<f64>, FrameStats) {
    let mut sequence = Sequence::load(path).expect("city loads");
    sequence.prepare_pipelines(backend, settings, |_, _| {});
    let mut stats = FrameStats::default();
    let seconds = (0..frames)
        .map(|frame| {
            stats = FrameStats::default();
            let start = Instant::now();
            let placed = sequence
                .advance(f64::from(frame) / 24.0, settings, &mut stats)
                .expect("camera");
            sequence
                .render(backend, &placed, settings, &mut stats)
                .expect("frame renders");
            start.elapsed().as_secs_f64()
        })
        .collect();
    (seconds, stats)
}

/// A frame's stages with their seconds, "demand 0.36, fill 0.98, ...".
fn stage_seconds(stats: &FrameStats) -> String {
    let stages: Vec<String> = (stats.stages.iter())
        .map(|(stage, seconds)| format!("{stage} {seconds:.2}"))
        .collect();
    let passes = stats.gpu.as_ref().map(|gpu| &gpu.passes.seconds);
    match passes.filter(|passes| !passes.is_empty()) {
        // The GPU's own time per pass, where the adapter times them.
        Some(passes) => {
            let passes: Vec<String> = (passes.iter())
                .map(|(pass, seconds)| format!("{pass} {seconds:.3}"))
                .collect();
            format!("{}; on the GPU: {}", stages.join(", "), passes.join(", "))
        }
        None => stages.join(", "),
    }
}

/// One frame of the scene at `path`, from scratch (its pipelines compiled
/// before the clock starts): its time and statistics.
fn render_cold(backend: &mut Backend, path: &Path, settings: &Settings) -> (f64, FrameStats) {
    let mut sequence = Sequence::load(path).expect("city loads");
    // On the GPU, the first case of a run would otherwise time the
    // driver's compile of its pipelines (BENCHMARKS.md, the H200's bench).
    sequence.prepare_pipelines(backend, settings, |_, _| {});
    let placed = sequence.place(settings).expect("camera");
    let mut stats = FrameStats::default();
    let start = Instant::now();
    sequence
        .render(backend, &placed, settings, &mut stats)
        .expect("frame renders");
    (start.elapsed().as_secs_f64(), stats)
}
