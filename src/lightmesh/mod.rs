//! The light mesh (paper section 2): a lattice of nodes with step `h`, each
//! carrying a lazily computed visibility mask with one bit per light, and
//! the interpolation that turns those masks into soft shadows by formula (2).
//!
//! In a frame it takes three stages after the hits are known: `demand`
//! (which (node, light) bits the shading points need), `fill` (compute the
//! missing ones, the only stage that sets visibility bits within a frame)
//! and `shade` (formula (2), with or without the point-to-node tests of
//! LMM). LMM1 runs one more, `enclosure`, after the fill: which nodes lie
//! inside closed geometry, which its formula (2) leaves out. Who else
//! writes the masks, and when, is in [`masks`].

pub(crate) mod agreement;
mod brick_codec;
pub mod cache;
pub mod demand;
pub mod enclosure;
pub mod faint;
pub mod fill;
pub mod interpolate;
pub mod invalidate;
pub mod kernel;
pub(crate) mod lamp_disk;
pub mod lattice;
pub mod masks;
pub mod penumbra;
pub mod persistent;
mod region_tree;
pub mod segments;
mod sight;
pub mod spacing;
mod wide;
pub(crate) mod wide_ball;

use std::sync::Arc;

use serde::Serialize;

use agreement::TileMemo;
use kernel::{Kernel, Weights};
use lattice::Lattice;
use masks::MaskStore;
use penumbra::Penumbra;

/// A light mesh with its masks; it outlives frames so masks are reused.
#[derive(Clone, Debug)]
pub struct LightMesh {
    pub lattice: Lattice,
    /// Interpolation radius in units of `h` (the paper's kI).
    pub ki: f32,
    /// How formula (2) weighs the nodes of a set.
    pub kernel: Kernel,
    /// How formula (2) sizes each light's set.
    pub penumbra: Penumbra,
    /// The share of a point's lamp light whose penumbrae it may leave at
    /// the half-ball's answer, as [`faint::budget_parts`] has it
    /// (`lightmesh.faint_lamps`).
    pub faint_parts: u32,
    masks: MaskStore,
    /// Bytes the masks may take before a frame is refused.
    memory_limit: usize,
    /// What tiles of the masks agree on, remembered across frames by the
    /// revision of the brick each was read from (`agreement`).
    tile_memo: Arc<TileMemo>,
}

/// Why the light mesh cannot serve a frame.
#[derive(Debug, thiserror::Error)]
pub enum LightMeshError {
    #[error(
        "the light mesh would need {needed_mib} MiB of node masks (limit {limit_mib} MiB) with h = {h} m; \
         raise h or lightmesh.max_memory_mib"
    )]
    TooLarge {
        needed_mib: usize,
        limit_mib: usize,
        h: f32,
    },
    #[error(
        "one level of the frame reads {needed_mib:.1} MiB of node masks on the GPU \
         (limit {limit_mib:.1} MiB) with h = {h} m; raise h or lightmesh.gpu_memory_mib"
    )]
    PoolTooSmall {
        needed_mib: f64,
        limit_mib: f64,
        h: f32,
    },
    #[error("h = {h} m is too small for a scene this far from its centre ({distance} m): node coordinates would overflow")]
    OutOfRange { h: f32, distance: f32 },
}

/// What the light mesh did in one frame (the `lightmesh` object of the
/// stats JSON).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LightMeshStats {
    pub h: f32,
    pub ki: f32,
    /// Nodes that had at least one bit computed this frame: the paper's N_LM.
    pub nodes_computed: u64,
    /// (node, light) bits computed this frame (one shadow segment each).
    pub bits_computed: u64,
    /// Bits this frame needed that earlier frames had computed.
    pub bits_reused: u64,
    /// Shaft queries of the fill (each settles a group of bits at once when
    /// nothing is in the way).
    pub fill_shafts: u64,
    /// Node-to-light segments the fill traced one by one, once against
    /// the static structure and once against the dynamic objects where it
    /// tests both (the GPU traces both in one segment: `gpu.segments_traced`).
    pub fill_segments: u64,
    /// Of those, segments answered by the triangle that blocked the
    /// previous node's segment to the same light, without a tree walk.
    pub fill_remembered: u64,
    /// Groups of a brick's nodes settled blocked at once: the triangle that
    /// blocked the first one hides the corners of their box.
    pub fill_hidden_groups: u64,
    /// (node, light) bits known after the frame: the cache the next frame
    /// draws on.
    pub bits_cached: u64,
    /// Nodes with any valid bit after the frame.
    pub nodes_cached: u64,
    /// Mean nodes per shading point after steps 1–2, over the points
    /// that walked their half-ball (all but `points_settled`).
    pub mean_candidates: f64,
    /// Mean size m of the interpolation set D_LM(P), over the same.
    pub mean_interp_set: f64,
    /// Mean step-3 (point-to-node) tests per point; 0 for LMM1.
    pub mean_p2n_tests: f64,
    /// LMM1's points whose nodes all around agree on each of their
    /// lights: formula (2) took their value without the half-ball.
    pub points_settled: u64,
    /// Points shaded by formula (1) because their set was empty.
    pub fallback_points: u64,
    /// Rays of `lightmesh.penumbra: blocker` and `wide`, per point and
    /// light its nodes (or with `wide` its wide set) disagree on: one or
    /// two closest-hit rays to find the blocker, and one segment per node
    /// of the lattice level's lamp disk.
    pub blocker_rays: u64,
    /// Level segments of `blocker` the CPU backend answered without a
    /// ray: from the mesh's masks, or as a neighbouring point of the same
    /// thread traced them (the GPU backend traces every one: its
    /// `blocker_rays` are the CPU's plus these).
    pub blocker_rays_remembered: u64,
    /// Nodes probed for lying inside closed geometry this frame (LMM1
    /// only; each node once per run).
    pub nodes_probed: u64,
    /// Enclosure flags LMM1 read that an earlier frame settled: the only
    /// thing derived from the masks that frames keep (agreement summaries
    /// and level answers are made anew in every frame).
    pub enclosure_reused: u64,
    /// Static bits imported from the disk cache this frame (only the
    /// frame that made the light mesh loads any).
    pub bits_loaded: u64,
    /// Shading points whose masks went through demand and fill: all of
    /// them on the CPU backend; on the GPU backend only those its mask
    /// pool did not serve yet (with reuse, a few).
    pub points_demanded: u64,
    /// Bricks brought up into the GPU backend's mask pool this frame (new
    /// to it, or edited since; only the words that changed travel); 0 on
    /// the CPU backend.
    pub bricks_uploaded: u64,
    /// Of those, bricks new to the pool, given a slot this frame; 0 on
    /// the CPU backend.
    pub bricks_inserted: u64,
    /// Bricks the GPU's mask pool evicted this frame to stay within
    /// `lightmesh.gpu_memory_mib`.
    pub bricks_evicted: u64,
}

impl LightMesh {
    pub fn new(lattice: Lattice, ki: f32, lights: usize, memory_limit: usize) -> LightMesh {
        LightMesh {
            lattice,
            ki,
            kernel: Kernel::Box,
            penumbra: Penumbra::Fixed,
            faint_parts: 0,
            masks: MaskStore::new(lights),
            memory_limit,
            tile_memo: Arc::default(),
        }
    }

    /// The memo of tiles' summaries, for a thread's [`agreement::Agreement`].
    pub fn tile_memo(&self) -> Arc<TileMemo> {
        Arc::clone(&self.tile_memo)
    }

    /// The faint lamps' budget ([`faint::budget_parts`]) where penumbrae
    /// are sized by rays, 0 where they are not (nothing to skip).
    pub fn faint_budget(&self) -> u32 {
        match self.penumbra.sizes_by_blocker() {
            true => self.faint_parts,
            false => 0,
        }
    }

    /// Radius r = kI·h of the interpolation ball.
    pub fn radius(&self) -> f32 {
        self.ki * self.lattice.h
    }

    /// The kernel's weights at radius r.
    pub fn weights(&self) -> Weights {
        Weights::new(self.kernel, self.radius())
    }

    pub fn masks(&self) -> &MaskStore {
        &self.masks
    }

    /// The error for a frame that would need `bytes` of masks and tables.
    fn too_large(&self, bytes: usize) -> LightMeshError {
        LightMeshError::TooLarge {
            needed_mib: bytes >> 20,
            limit_mib: self.memory_limit >> 20,
            h: self.lattice.h,
        }
    }
}
