//! Which eight-child test the wide walk runs: the choice, made once per BVH
//! from what the CPU has ([`NodeTestPath`]), and the form the walk's loop
//! calls ([`ChildTest`]). Both tests answer bit for bit alike; tests
//! compare them.

use super::super::node_test::{RayLanes, TraversalRay};
use super::super::wide::WideNode;

/// Which code tests a wide node's children; only their speed differs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeTestPath {
    /// [`TraversalRay::enter_children`]: two 128-bit passes, on any CPU.
    Portable,
    /// One 256-bit pass, on a CPU found to have AVX2.
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2Detected),
}

impl NodeTestPath {
    /// The widest test this CPU runs.
    pub fn detect() -> NodeTestPath {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return NodeTestPath::Avx2(Avx2Detected(()));
        }
        NodeTestPath::Portable
    }
}

/// Proof that the CPU has AVX2, which the AVX2 walk's safety rests on:
/// only [`NodeTestPath::detect`] makes one.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx2Detected(());

/// A wide node's eight-child test as the walk's loop calls it. Structs
/// rather than closures, so that `#[inline(always)]` holds: LLVM kept a
/// closure holding the test as a call per node.
pub trait ChildTest {
    /// Which children the ray enters within `t_cull`, by rank: bit `r`
    /// for child `r ^ flip`; and every child's entry `t`, by slot.
    fn ranked_children(
        &self,
        ray: &TraversalRay,
        node: &WideNode,
        t_cull: f32,
        flip: u32,
    ) -> (u32, [f32; 8]);
}

/// The portable test, with the lanes of the ray it walks.
pub struct PortableTest(pub RayLanes);

impl ChildTest for PortableTest {
    #[inline(always)]
    fn ranked_children(
        &self,
        ray: &TraversalRay,
        node: &WideNode,
        t_cull: f32,
        flip: u32,
    ) -> (u32, [f32; 8]) {
        let (hits, entry) = ray.enter_children(&self.0, node, t_cull);
        (flip_slots(hits, flip), entry)
    }
}

/// The AVX2 test, for rays with no axis-parallel direction.
#[cfg(target_arch = "x86_64")]
pub struct Avx2Test(pub Avx2Detected);

#[cfg(target_arch = "x86_64")]
impl ChildTest for Avx2Test {
    #[inline(always)]
    fn ranked_children(
        &self,
        ray: &TraversalRay,
        node: &WideNode,
        t_cull: f32,
        flip: u32,
    ) -> (u32, [f32; 8]) {
        // SAFETY: `self.0` proves that the CPU has AVX2.
        unsafe { ray.enter_children_avx2(node, t_cull, flip) }
    }
}

/// Moves bit `i` of an eight-bit mask to bit `i ^ flip`.
#[inline(always)]
fn flip_slots(mut mask: u32, flip: u32) -> u32 {
    if flip & 1 != 0 {
        mask = (mask & 0x55) << 1 | (mask >> 1) & 0x55;
    }
    if flip & 2 != 0 {
        mask = (mask & 0x33) << 2 | (mask >> 2) & 0x33;
    }
    if flip & 4 != 0 {
        mask = (mask & 0x0f) << 4 | (mask >> 4) & 0x0f;
    }
    mask
}
