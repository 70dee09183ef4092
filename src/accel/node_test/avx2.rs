//! [`TraversalRay::enter_children`] in one 256-bit pass for CPUs with AVX2,
//! where the portable test takes two 128-bit ones. It is always inlined,
//! into the traversal loop that [`traverse`](super::super::traverse)
//! compiles for AVX2 as a whole and chooses at run time: a function of its
//! own with `#[target_feature]` is left to LLVM's inlining heuristics, which
//! kept it (and the intrinsics' closures in it) as calls, costing more than
//! the wide test saves.
//!
//! It must answer bit for bit as the portable test does, or the two paths
//! would disagree on ties and on rays aimed at edges: the same operations
//! in the same order, and `min`/`max` with the same operand order as glam's
//! `Vec4::min`/`max` (`minps`/`maxps` return their second operand when
//! either is NaN, so `max(a, b)` and `max(b, a)` differ). No FMA: a fused
//! `(plane - origin) * inv` would round once where the portable test rounds
//! twice.

use std::arch::x86_64::{
    __m256, _mm256_cmp_ps, _mm256_max_ps, _mm256_min_ps, _mm256_movemask_ps, _mm256_mul_ps,
    _mm256_permutevar8x32_ps, _mm256_set1_epi32, _mm256_set1_ps, _mm256_setr_epi32,
    _mm256_setzero_ps, _mm256_sub_ps, _mm256_xor_si256, _CMP_LE_OS,
};

use super::{TraversalRay, BINARY_SCALE};
use crate::accel::wide::WideNode;

impl TraversalRay {
    /// [`TraversalRay::enter_children`], eight lanes at once, for rays
    /// with no axis-parallel direction: those need the portable test's
    /// exact slab fix-up, rare and not worth a second copy (and checking
    /// for it once per ray rather than per node keeps this loop short).
    /// The mask comes by rank: bit `r` tells whether child `r ^ flip` is
    /// entered, the lanes reordered in one permutation where moving the
    /// mask's bits took a dozen instructions.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub unsafe fn enter_children_avx2(
        &self,
        node: &WideNode,
        t_cull: f32,
        flip: u32,
    ) -> (u32, [f32; 8]) {
        debug_assert!(!self.has_parallel_axis());
        let t_cull = _mm256_set1_ps(t_cull * BINARY_SCALE);
        let mut near = _mm256_setzero_ps();
        let mut far = _mm256_set1_ps(f32::INFINITY);
        // A loop, not `map` with closures: a closure is compiled without
        // AVX2, so the intrinsics it calls would not inline into it.
        for k in 0..3 {
            let planes = &node.planes[k];
            let side = self.near_side(k);
            let origin = _mm256_set1_ps(self.origin[k]);
            let inv_direction = _mm256_set1_ps(self.inv_direction[k]);
            let near_k = _mm256_sub_ps(eight_lanes(planes[side]), origin);
            let far_k = _mm256_sub_ps(eight_lanes(planes[side ^ 1]), origin);
            near = _mm256_max_ps(near, _mm256_mul_ps(near_k, inv_direction));
            far = _mm256_min_ps(far, _mm256_mul_ps(far_k, inv_direction));
        }
        let limit = _mm256_min_ps(_mm256_mul_ps(far, _mm256_set1_ps(BINARY_SCALE)), t_cull);
        let entered = _mm256_cmp_ps::<_CMP_LE_OS>(near, limit);
        let by_rank = _mm256_xor_si256(
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            _mm256_set1_epi32(flip as i32),
        );
        let ranks = _mm256_movemask_ps(_mm256_permutevar8x32_ps(entered, by_rank)) as u32;
        (ranks, bytemuck::cast(near))
    }
}

/// Children 0–3 then 4–7 of one axis and side, as the node stores them.
#[inline(always)]
fn eight_lanes(halves: [glam::Vec4; 2]) -> __m256 {
    bytemuck::cast(halves)
}
