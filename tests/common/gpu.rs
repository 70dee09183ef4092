//! The GPU backend for tests that compare it with the CPU's.

use lmanim::backend::{Backend, GpuBackend};
use lmanim::output::Image;
use lmanim::scene::SceneDesc;
use lmanim::sequence::Sequence;
use lmanim::settings::Settings;

/// The GPU backend, or None (with the reason on stderr) off CI when no
/// adapter exists; under CI a missing adapter fails the test.
pub fn backend() -> Option<GpuBackend> {
    match GpuBackend::new(Some(2)) {
        Ok(gpu) => Some(gpu),
        Err(error) if std::env::var_os("CI").is_none() => {
            eprintln!("skipped: {error}");
            None
        }
        Err(error) => panic!("CI must have a GPU adapter (mesa-vulkan-drivers): {error}"),
    }
}

/// The GPU backend ready to render, and whether its adapter rounds as the
/// CPU does (then its frames must be the CPU's bits); None as [`backend`].
pub fn backend_to_compare() -> Option<(Backend, bool)> {
    let gpu = backend()?;
    let exact = gpu.rounds_as_the_cpu();
    Some((Backend::Gpu(Box::new(gpu)), exact))
}

/// Renders `scene`'s first frame by `settings` on the GPU backend and holds
/// it to the CPU backend's frame `on_cpu`: the same bits where the adapter
/// rounds as the CPU does, finite everywhere else.
pub fn assert_gpu_frame_is(scene: &SceneDesc, settings: &Settings, on_cpu: &Image) {
    let Some((mut gpu, exact)) = backend_to_compare() else {
        return;
    };
    let (on_gpu, _) = super::render_on(&mut gpu, scene.clone(), settings);
    if exact {
        assert!(
            on_gpu == *on_cpu,
            "{}: the GPU's frame differs from the CPU's",
            settings.method
        );
    } else {
        assert!(on_gpu.pixels.iter().all(|p| p.is_finite()));
    }
}

/// On the GPU backend, the mask pool's resident slots hold `sequence`'s
/// light-mesh bricks word for word after `frame`: what the pool sent up
/// (words of bricks edited by the fill, by invalidation, by the disk
/// cache) made the GPU's copy the store's. Nothing to hold elsewhere.
pub fn assert_pool_holds_the_store(backend: &Backend, sequence: &Sequence, frame: u32) {
    let (Backend::Gpu(gpu), Some(mesh)) = (backend, sequence.light_mesh()) else {
        return;
    };
    let stale = gpu.stale_mask_bricks(mesh).expect("the pool read back");
    let first = &stale[..stale.len().min(4)];
    assert!(
        stale.is_empty(),
        "frame {frame}: {} stale bricks, {first:?}…",
        stale.len()
    );
}
