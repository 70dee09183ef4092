//! The GPU backend for tests that compare it with the CPU's.

use lmanim::backend::GpuBackend;

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
