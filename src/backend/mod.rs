//! Backends run a frame's stages on some hardware. The CPU backend (rayon)
//! is the reference; a wgpu backend will implement the same stages as GPU
//! passes. The core (scene, accel, render) never knows which one runs it.

pub mod cpu;
mod sampling;

pub use cpu::CpuBackend;
