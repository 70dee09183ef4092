//! The GPU backend for tests that compare it with the CPU's.

use lmanim::backend::{Backend, GpuBackend};
use lmanim::output::Image;
use lmanim::scene::SceneDesc;
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
