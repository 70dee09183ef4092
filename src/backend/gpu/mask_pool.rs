//! The light mesh's masks on the GPU: a pool of brick slots in one buffer
//! and a directory that finds a brick's slot by its coordinates.
//!
//! A slot holds one brick of the CPU's [`MaskStore`] as the GPU reads it:
//! per node and u32 word of 32 lights, which of them it sees and which of
//! those bits are valid, side by side (the store's two layers folded as
//! `NodeMask::visible` and `valid` fold them), so that the GPU's fill
//! writes a bit's pair of words; then the brick's enclosure flags.
//! Folding halves the store's four groups, and u32 words halve them again
//! for scenes of up to 32 lights, so more bricks fit the adapter's
//! largest binding.
//!
//! The store stays the authority: demand, fill, invalidation and the disk
//! cache edit it, and the pool follows. Slots stay resident across frames;
//! [`MaskPool::refresh`] brings up the resident bricks edited since their
//! copy (each edit moves a brick's revision) before a level's coverage
//! pass reads them, and [`MaskPool::admit`] the bricks the level's demand
//! named.
//!
//! What goes up is only what changed. The pool keeps a mirror of every
//! slot as the GPU holds it; a brick brought up is folded and compared
//! with its slot's mirror, and only the words that differ travel, as
//! (word, value) patches that `patch_pool.wgsl` writes in place, or as
//! the whole slot where most of it changed (a brick new to its slot). A
//! fill or an invalidation edits a few nodes of a brick, so a steady
//! frame of a fly-through sends a small part of each brick it touches
//! instead of all of it ([`SlotEdits`]).
//!
//! The pool is bounded (`lightmesh.gpu_memory_mib`, and the adapter's
//! largest binding): bricks the current level does not read are evicted,
//! least recently read first; a level that reads more bricks than the
//! bound holds is refused with the light mesh's error naming h and the
//! limit. Which slot a brick gets never changes an image: the shaders find
//! it through the directory.
//!
//! The directory is an open-addressing hash table (linear probing, at most
//! half full), rebuilt on the CPU when the resident set changes and
//! uploaded whole: a few thousand entries of 16 bytes. Its header carries
//! the lattice and the interpolation's parameters.

use bytemuck::{Pod, Zeroable};
use glam::IVec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::context::{GpuContext, GpuError};
use super::contract::{GROUPS, ITEMS};
use super::pass::{Dispatch, WorldPass, BATCH};
use super::recording::Recording;
use super::scene::{storage, GpuScene};
use crate::backend::RenderError;
use crate::lightmesh::masks::{BrickEnclosure, MaskStore, BRICK_NODES, BRICK_WORDS};
use crate::lightmesh::{LightMesh, LightMeshError};

/// `light_mesh.wgsl`'s `MeshHeader`: the lattice, the interpolation
/// radius, the light words per node group, and the directory's size.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MeshHeader {
    pub origin: [f32; 3],
    pub h: f32,
    pub radius: f32,
    /// u32 words per group of a node (`ceil(lights / 32)`).
    pub light_words: u32,
    /// Directory entries minus one (a power of two minus one).
    pub entry_mask: u32,
    /// 1 for LMM (point-to-node segments), 0 for LMM1.
    pub point_to_node_tests: u32,
    /// The kernel's 1/r², as the CPU rounds it (`kernel::Weights`).
    pub inverse_radius_squared: f32,
    /// The kernel's code (`contract::KERNEL_BOX`, `KERNEL_SMOOTH`).
    pub kernel: u32,
    /// How lamps' sets are sized (`lightmesh.penumbra`): its code
    /// (`contract::PENUMBRA_FIXED`, `PENUMBRA_BLOCKER`, `PENUMBRA_WIDE`).
    pub penumbra: u32,
    /// The faint lamps' budget (`LightMesh::faint_budget`), 0 for none.
    pub faint_parts: u32,
}

/// A directory entry: a brick's coordinates and its slot, or
/// [`EMPTY_SLOT`] where no brick is.
pub type Entry = [i32; 4];

/// The slot field of an empty directory entry.
pub const EMPTY_SLOT: i32 = -1;

/// Where probing for `brick` starts (`light_mesh.wgsl`'s
/// `directory_hash`): wrapping products of the coordinates with odd
/// constants, mixed by xor.
pub fn directory_hash(brick: IVec3) -> u32 {
    (brick.x as u32).wrapping_mul(0x8da6_b343)
        ^ (brick.y as u32).wrapping_mul(0xd816_3841)
        ^ (brick.z as u32).wrapping_mul(0xcb1a_b31f)
}

/// A resident brick: its slot, the store revision it was copied at, and
/// the last update that read it.
#[derive(Clone, Copy, Debug)]
struct Resident {
    slot: u32,
    revision: u64,
    used: u64,
}

/// Bricks on the GPU, mirroring one [`MaskStore`].
pub struct MaskPool {
    /// The store mirrored and the u32 light words per node group; another
    /// store (a new light mesh) empties the pool.
    store: u64,
    light_words: usize,
    /// Bytes the slots may take.
    limit: usize,
    slots: wgpu::Buffer,
    capacity: usize,
    resident: FxHashMap<IVec3, Resident>,
    /// The words of the slots handed out, as the GPU holds them once the
    /// edits made so far are written: what a brick's fold is compared
    /// with, so that only the words that changed go up.
    mirror: Vec<u32>,
    /// Slots freed by eviction, reused before the pool grows.
    free: Vec<u32>,
    /// Slots handed out so far (below `capacity`).
    allocated: usize,
    /// Updates so far: the clock of `Resident::used`.
    updates: u64,
    directory: Option<(MeshHeader, wgpu::Buffer)>,
    /// Whether the resident set changed since the directory was built.
    directory_stale: bool,
    /// The points the last coverage pass found the pool does not serve:
    /// what sizes the room the next one has for copies of its own
    /// ([`MaskPool::gather_room`]).
    unserved: usize,
}

/// Copies of unserved points a coverage pass has room for beyond the last
/// pass's count: a frame that reuses masks leaves a similar number, and
/// one wait brings them back with the flags; where more are left, a
/// gather brings them back after a second wait.
const GATHER_MARGIN: usize = 1024;

/// What one update uploaded, for the stats.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoolUpload {
    /// Bricks whose slot changed (new to the pool, or edited since their
    /// copy), whole or word by word.
    pub bricks: u64,
    /// Bricks given a slot: new to the pool.
    pub inserted: u64,
    pub evicted: u64,
}

impl MaskPool {
    /// An empty pool whose slots may take `limit` bytes.
    pub fn new(context: &GpuContext, limit: usize) -> Result<MaskPool, GpuError> {
        Ok(MaskPool {
            store: u64::MAX,
            light_words: 0,
            limit,
            slots: slot_buffer(context, 16)?,
            capacity: 0,
            resident: FxHashMap::default(),
            mirror: Vec::new(),
            free: Vec::new(),
            allocated: 0,
            updates: 0,
            directory: None,
            directory_stale: true,
            unserved: 0,
        })
    }

    /// u32 light words per node group for `lights` lights.
    pub fn light_words(lights: usize) -> usize {
        lights.div_ceil(32).max(1)
    }

    /// Bytes of one slot with `light_words` u32 words per node group.
    pub fn slot_bytes(light_words: usize) -> usize {
        BRICK_NODES * GROUPS as usize * light_words * size_of::<u32>()
            + 2 * BRICK_WORDS * size_of::<u64>()
    }

    /// Brings every resident brick up to `mesh`'s store (invalidation
    /// edits bricks no demand names) and the directory up to the pool,
    /// so that a coverage pass reads current masks; returns the slots'
    /// edits, for [`SlotEdits::write`], and how many bricks they change.
    pub fn refresh(
        &mut self,
        context: &GpuContext,
        mesh: &LightMesh,
        point_to_node_tests: bool,
    ) -> Result<(SlotEdits, u64), GpuError> {
        let store = mesh.masks();
        if store.id() != self.store {
            self.empty(store);
        }
        let stale: Vec<(IVec3, u32)> = (self.resident.iter_mut())
            .filter_map(|(&brick, resident)| {
                let revision = store.brick_revision(brick)?;
                (revision != resident.revision).then(|| {
                    resident.revision = revision;
                    (brick, resident.slot)
                })
            })
            .collect();
        let mut edits = SlotEdits::default();
        let changed = self.bring_up(store, &stale, &mut edits) as u64;
        self.build_directory(context, mesh, point_to_node_tests)?;
        Ok((edits, changed))
    }

    /// Makes `demanded` (sorted, no repeats) resident and current for a
    /// level whose other points read the slots set in `read_slots` (a bit
    /// per slot, from the coverage pass): bricks neither names are evicted,
    /// least recently read first, when the bound is reached. Returns the
    /// slots' edits, for [`SlotEdits::write`].
    pub fn admit(
        &mut self,
        context: &GpuContext,
        mesh: &LightMesh,
        demanded: &[IVec3],
        read_slots: &[u32],
        point_to_node_tests: bool,
    ) -> Result<(SlotEdits, PoolUpload), RenderError> {
        let store = mesh.masks();
        self.updates += 1;
        let now = self.updates;
        let is_read = |slot: u32| {
            read_slots
                .get(slot as usize / 32)
                .is_some_and(|&bits| bits >> (slot % 32) & 1 == 1)
        };
        for resident in self.resident.values_mut() {
            if is_read(resident.slot) {
                resident.used = now;
            }
        }
        let mut missing = 0;
        for brick in demanded {
            match self.resident.get_mut(brick) {
                Some(resident) => resident.used = now,
                None => missing += 1,
            }
        }
        let slot_bytes = Self::slot_bytes(self.light_words);
        let binding = context.limits.max_storage_buffer_binding_size as usize;
        let limit_slots = self.limit.min(binding) / slot_bytes;
        let reading = missing + self.resident.values().filter(|r| r.used == now).count();
        if reading > limit_slots {
            let mib = |bytes: usize| bytes as f64 / f64::from(1 << 20);
            return Err(RenderError::LightMesh(LightMeshError::PoolTooSmall {
                needed_mib: mib(reading * slot_bytes),
                limit_mib: mib(self.limit),
                h: mesh.lattice.h,
            }));
        }
        let mut upload = PoolUpload {
            evicted: self.make_room(missing, limit_slots),
            ..PoolUpload::default()
        };
        let wanted = (self.allocated + missing.saturating_sub(self.free.len())).min(limit_slots);
        if wanted > self.capacity {
            self.grow(context, wanted.max(2 * self.capacity).min(limit_slots))?;
        }
        let mut stale = Vec::new();
        for &brick in demanded {
            let Some(revision) = store.brick_revision(brick) else {
                continue;
            };
            let resident = match self.resident.get_mut(&brick) {
                Some(resident) => resident,
                None => {
                    let slot = self.free.pop().unwrap_or_else(|| {
                        self.allocated += 1;
                        (self.allocated - 1) as u32
                    });
                    self.directory_stale = true;
                    upload.inserted += 1;
                    self.resident.entry(brick).or_insert(Resident {
                        slot,
                        revision: u64::MAX,
                        used: now,
                    })
                }
            };
            if resident.revision != revision {
                resident.revision = revision;
                stale.push((brick, resident.slot));
            }
        }
        let mut edits = SlotEdits::default();
        upload.bricks = self.bring_up(store, &stale, &mut edits) as u64;
        self.build_directory(context, mesh, point_to_node_tests)?;
        Ok((edits, upload))
    }

    /// Folds each of `bricks` (with its slot) of `store` into the words its
    /// slot should hold and adds to `edits` those that differ from what
    /// the slot holds (all of them, as one write, where most differ);
    /// returns how many bricks had any. The folds and comparisons run in
    /// parallel; the edits are taken in `bricks`' order, so what goes up
    /// does not depend on the threads.
    fn bring_up(
        &mut self,
        store: &MaskStore,
        bricks: &[(IVec3, u32)],
        edits: &mut SlotEdits,
    ) -> usize {
        let slot_words = self.slot_words();
        let mirror = &self.mirror;
        let folds: Vec<(usize, Vec<u32>, Vec<usize>)> = (bricks.par_iter())
            .filter_map(|&(brick, slot)| {
                let words = fold_brick(store, brick)?;
                let start = slot as usize * slot_words;
                let held = &mirror[start..start + slot_words];
                let changed: Vec<usize> =
                    (0..slot_words).filter(|&i| held[i] != words[i]).collect();
                (!changed.is_empty()).then_some((start, words, changed))
            })
            .collect();
        let brought_up = folds.len();
        for (start, words, changed) in folds {
            self.mirror[start..start + slot_words].copy_from_slice(&words);
            if 2 * changed.len() >= slot_words {
                edits.slots.push((start, words));
            } else {
                let word = |i: usize| [(start + i) as u32, words[i]];
                edits.words.extend(changed.iter().map(|&i| word(i)));
            }
        }
        brought_up
    }

    /// The pool word where each of `bricks`' slots starts, for a pass
    /// that writes their bits in place; None for a brick that has none.
    pub fn slot_starts(&self, bricks: &[IVec3]) -> Vec<Option<usize>> {
        let slot_words = self.slot_words();
        (bricks.iter())
            .map(|brick| Some(self.resident.get(brick)?.slot as usize * slot_words))
            .collect()
    }

    /// Takes the words a pass wrote into `bricks`' slots on the GPU as
    /// held, now that `store` holds the same bits: each resident brick's
    /// mirror becomes its fold, at the store's revision, and nothing
    /// goes up.
    pub fn written_on_gpu(&mut self, store: &MaskStore, bricks: &[IVec3]) {
        let slot_words = self.slot_words();
        let resident = &self.resident;
        // A brick whose revision did not move since its slot took it is
        // folded in the mirror already: the pass wrote nothing the store
        // did not take (every answer merged is an edit).
        let folds: Vec<(IVec3, u64, Vec<u32>)> = (bricks.par_iter())
            .filter_map(|&brick| {
                let revision = store.brick_revision(brick)?;
                if resident.get(&brick)?.revision == revision {
                    return None;
                }
                Some((brick, revision, fold_brick(store, brick)?))
            })
            .collect();
        for (brick, revision, words) in folds {
            let resident = (self.resident.get_mut(&brick)).expect("a resident brick, as above");
            resident.revision = revision;
            let start = resident.slot as usize * slot_words;
            self.mirror[start..start + slot_words].copy_from_slice(&words);
        }
    }

    /// The bricks whose slots do not hold their fold of `store`, as the
    /// GPU holds them now (read back; a test's check of the mirror and of
    /// every edit written); empty where the pool mirrors another store.
    pub fn stale_bricks(
        &self,
        context: &GpuContext,
        store: &MaskStore,
    ) -> Result<Vec<IVec3>, GpuError> {
        if store.id() != self.store || self.allocated == 0 {
            return Ok(Vec::new());
        }
        let slot_words = self.slot_words();
        let why = "the mask pool's slots, to compare with the store";
        let held: Vec<u32> =
            Recording::new(context).read_back(why, &self.slots, self.allocated * slot_words)?;
        let mut stale: Vec<IVec3> = (self.resident.iter())
            .filter(|(&brick, resident)| {
                let start = resident.slot as usize * slot_words;
                let slot = start..start + slot_words;
                let folded = fold_brick(store, brick);
                folded.as_deref() != Some(&held[slot.clone()])
                    || held[slot.clone()] != self.mirror[slot]
            })
            .map(|(&brick, _)| brick)
            .collect();
        stale.sort_unstable_by_key(|brick| brick.to_array());
        Ok(stale)
    }

    /// u32 words of one slot.
    fn slot_words(&self) -> usize {
        Self::slot_bytes(self.light_words) / size_of::<u32>()
    }

    /// How many unserved points the next coverage pass copies out: a
    /// quarter more than the last pass left, and a margin.
    pub fn gather_room(&self) -> usize {
        self.unserved + self.unserved / 4 + GATHER_MARGIN
    }

    /// Records how many points a coverage pass found the pool does not
    /// serve.
    pub fn served(&mut self, unserved: usize) {
        self.unserved = unserved;
    }

    /// Slots the pool holds now: the bits of a coverage pass's
    /// `read_slots`.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Entries of the directory, empty ones included.
    pub fn directory_entries(&self) -> usize {
        (self.directory.as_ref()).map_or(0, |(header, _)| header.entry_mask as usize + 1)
    }

    /// The slots and the directory, for binding.
    pub fn buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        let (_, directory) = self
            .directory
            .as_ref()
            .expect("the directory is built by every update");
        (&self.slots, directory)
    }

    /// Forgets every brick: the pool now mirrors `store`.
    fn empty(&mut self, store: &MaskStore) {
        self.store = store.id();
        self.light_words = Self::light_words(store.lights());
        self.resident.clear();
        self.mirror.clear();
        self.free.clear();
        self.allocated = 0;
        self.capacity = 0;
        self.directory_stale = true;
    }

    /// Frees slots for `missing` new bricks where the pool is at its
    /// bound, evicting the least recently read bricks that the current
    /// level does not read; returns how many were evicted.
    fn make_room(&mut self, missing: usize, limit_slots: usize) -> u64 {
        let available = self.free.len() + (limit_slots - self.allocated.min(limit_slots));
        if missing <= available {
            return 0;
        }
        let now = self.updates;
        let mut idle: Vec<(u64, [i32; 3])> = (self.resident.iter())
            .filter(|(_, resident)| resident.used < now)
            .map(|(brick, resident)| (resident.used, brick.to_array()))
            .collect();
        idle.sort_unstable();
        let evict = missing - available;
        for &(_, brick) in &idle[..evict] {
            let resident = self.resident.remove(&IVec3::from_array(brick));
            self.free.extend(resident.map(|resident| resident.slot));
        }
        self.directory_stale = true;
        evict as u64
    }

    /// A buffer of `capacity` slots holding the resident ones.
    fn grow(&mut self, context: &GpuContext, capacity: usize) -> Result<(), GpuError> {
        let slot_bytes = Self::slot_bytes(self.light_words);
        let grown = context.checked("growing the mask pool", || {
            slot_buffer(context, (capacity * slot_bytes) as u64)
        })?;
        if self.allocated > 0 {
            let mut encoder = context.device.create_command_encoder(&Default::default());
            let used = (self.allocated * slot_bytes) as u64;
            encoder.copy_buffer_to_buffer(&self.slots, 0, &grown, 0, used);
            context.queue.submit([encoder.finish()]);
        }
        self.slots = grown;
        self.capacity = capacity;
        // A new buffer reads zero beyond the slots copied.
        self.mirror
            .resize(capacity * slot_bytes / size_of::<u32>(), 0);
        Ok(())
    }

    /// Rebuilds and uploads the directory where the resident set or the
    /// header changed.
    fn build_directory(
        &mut self,
        context: &GpuContext,
        mesh: &LightMesh,
        point_to_node_tests: bool,
    ) -> Result<(), GpuError> {
        let entries = (2 * self.resident.len()).next_power_of_two().max(16);
        let weights = mesh.weights();
        let header = MeshHeader {
            origin: mesh.lattice.origin.to_array(),
            h: mesh.lattice.h,
            radius: mesh.radius(),
            light_words: self.light_words as u32,
            entry_mask: entries as u32 - 1,
            point_to_node_tests: point_to_node_tests as u32,
            inverse_radius_squared: weights.inverse_radius_squared(),
            // The contract's codes are the enums' discriminants.
            kernel: weights.kernel() as u32,
            penumbra: mesh.penumbra as u32,
            faint_parts: mesh.faint_budget(),
        };
        if !self.directory_stale && self.directory.as_ref().is_some_and(|(h, _)| *h == header) {
            return Ok(());
        }
        let mut table = vec![[0, 0, 0, EMPTY_SLOT]; entries];
        for (brick, resident) in &self.resident {
            let mut at = directory_hash(*brick) as usize & (entries - 1);
            while table[at][3] != EMPTY_SLOT {
                at = (at + 1) & (entries - 1);
            }
            table[at] = [brick.x, brick.y, brick.z, resident.slot as i32];
        }
        let mut bytes = bytemuck::bytes_of(&header).to_vec();
        bytes.extend_from_slice(bytemuck::cast_slice(&table));
        let buffer = storage(context, "mask directory", &bytes)?;
        self.directory = Some((header, buffer));
        self.directory_stale = false;
        Ok(())
    }
}

fn slot_buffer(context: &GpuContext, bytes: u64) -> Result<wgpu::Buffer, GpuError> {
    context.check_binding("mask pool", bytes)?;
    Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("mask pool"),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// `brick`'s folded node masks and enclosure flags from `store`, as its
/// slot holds them; None where the store has no such brick.
fn fold_brick(store: &MaskStore, brick: IVec3) -> Option<Vec<u32>> {
    let bits = store.brick(brick)?;
    let light_words = MaskPool::light_words(store.lights());
    let mut words = vec![0; MaskPool::slot_bytes(light_words) / size_of::<u32>()];
    let (nodes, flags) = words.split_at_mut(BRICK_NODES * GROUPS as usize * light_words);
    for (slot, node) in nodes
        .chunks_exact_mut(GROUPS as usize * light_words)
        .enumerate()
    {
        let mask = store.slot_mask(bits, slot);
        for (word, pair) in node.chunks_exact_mut(2).enumerate() {
            let half = |bits: u64| (bits >> (32 * (word % 2))) as u32;
            pair[0] = half(mask.visible(word / 2));
            pair[1] = half(mask.valid(word / 2));
        }
    }
    let BrickEnclosure { known, enclosed } = store.enclosure(brick);
    let (known_words, enclosed_words) = flags.split_at_mut(flags.len() / 2);
    known_words.copy_from_slice(bytemuck::cast_slice(&known));
    enclosed_words.copy_from_slice(bytemuck::cast_slice(&enclosed));
    Some(words)
}

/// What the slots must be given to hold their bricks' folds: whole slots,
/// and single words where a few of a slot's changed.
#[derive(Debug, Default)]
pub struct SlotEdits {
    /// The first word of a slot, and its words.
    slots: Vec<(usize, Vec<u32>)>,
    /// A word of the pool, and its value.
    words: Vec<[u32; 2]>,
}

impl SlotEdits {
    /// Writes the edits into `pool`'s slots, after the work recorded so
    /// far and before what is recorded next: what was recorded is
    /// submitted first, since whole slots go by the queue's writes, which
    /// a submission runs ahead of its own commands; the words go by
    /// `patch`, recorded.
    pub fn write(
        self,
        context: &GpuContext,
        patch: &WorldPass,
        scene: &GpuScene,
        recording: &mut Recording,
        pool: &MaskPool,
    ) -> Result<(), GpuError> {
        if self.slots.is_empty() && self.words.is_empty() {
            return Ok(());
        }
        recording.submit();
        for (start, words) in &self.slots {
            let offset = (start * size_of::<u32>()) as u64;
            context.write(&pool.slots, offset, bytemuck::cast_slice(words));
        }
        for words in self.words.chunks(BATCH) {
            let items = storage(context, "mask pool words", words)?;
            let dispatch = Dispatch::new(scene, words.len());
            let reads = [(ITEMS, &items)];
            patch.record(context, recording.encoder(), dispatch, &reads, &pool.slots);
        }
        Ok(())
    }
}
