//! The light mesh's masks on the GPU: a pool of brick slots in one buffer
//! and a directory that finds a brick's slot by its coordinates.
//!
//! A slot is a copy of one brick of the CPU's [`MaskStore`], in the
//! store's own layout (per node, the four groups of words: static
//! visibility and validity, dynamic occlusion and validity; then the
//! brick's enclosure flags), so keeping the pool current is a copy of the
//! bricks whose revision moved, never a conversion. The store stays the
//! authority: demand, fill, invalidation and the disk cache edit it, and
//! the pool follows with an upload of what changed. Slots stay resident
//! across frames; a frame uploads only the bricks it reads that are new
//! to the pool or were edited since their upload.
//!
//! The pool is bounded (`lightmesh.gpu_memory_mib`): bricks the current
//! level does not read are evicted, least recently used first; a level
//! that reads more bricks than the bound holds is refused with the light
//! mesh's error naming h and the limit. Which slot a brick gets never
//! changes an image: the shader finds it through the directory.
//!
//! The directory is an open-addressing hash table (linear probing, at most
//! half full), rebuilt on the CPU when the resident set changes and
//! uploaded whole: a few thousand entries of 16 bytes. Its header carries
//! the lattice and the interpolation's parameters.

use bytemuck::{Pod, Zeroable};
use glam::IVec3;
use rustc_hash::FxHashMap;

use super::context::{GpuContext, GpuError};
use super::scene::storage;
use crate::backend::RenderError;
use crate::lightmesh::masks::{BrickEnclosure, MaskStore, BRICK_NODES, BRICK_WORDS};
use crate::lightmesh::{LightMesh, LightMeshError};

/// Words (u64) of node masks per node: the store's four groups.
const GROUPS: usize = 4;

/// `light_mesh.wgsl`'s `MeshHeader`: the lattice, the interpolation
/// radius, the light words per node group, and the directory's size.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MeshHeader {
    pub origin: [f32; 3],
    pub h: f32,
    pub radius: f32,
    /// u64 words per group of a node (`ceil(lights / 64)`).
    pub words: u32,
    /// Directory entries minus one (a power of two minus one).
    pub entry_mask: u32,
    /// 1 for LMM (point-to-node segments), 0 for LMM1.
    pub point_to_node_tests: u32,
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
    /// The store mirrored and its words per group; another store (a new
    /// light mesh) empties the pool.
    store: u64,
    words: usize,
    /// Bytes the slots may take.
    limit: usize,
    slots: wgpu::Buffer,
    capacity: usize,
    resident: FxHashMap<IVec3, Resident>,
    /// Slots freed by eviction, reused before the pool grows.
    free: Vec<u32>,
    /// Slots handed out so far (below `capacity`).
    allocated: usize,
    /// Updates so far: the clock of `Resident::used`.
    updates: u64,
    directory: Option<(MeshHeader, wgpu::Buffer)>,
    /// Whether the resident set changed since the directory was built.
    directory_stale: bool,
}

/// What one update uploaded, for the stats.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoolUpload {
    pub bricks: u64,
    pub evicted: u64,
}

impl MaskPool {
    /// An empty pool whose slots may take `limit` bytes.
    pub fn new(context: &GpuContext, limit: usize) -> Result<MaskPool, GpuError> {
        Ok(MaskPool {
            store: u64::MAX,
            words: 0,
            limit,
            slots: slot_buffer(context, 16)?,
            capacity: 0,
            resident: FxHashMap::default(),
            free: Vec::new(),
            allocated: 0,
            updates: 0,
            directory: None,
            directory_stale: true,
        })
    }

    /// Bytes of one slot with `words` light words per group.
    pub fn slot_bytes(words: usize) -> usize {
        (BRICK_NODES * GROUPS * words + 2 * BRICK_WORDS) * size_of::<u64>()
    }

    /// Bricks resident now.
    pub fn resident(&self) -> usize {
        self.resident.len()
    }

    /// Brings the pool up to `mesh`'s store for a level that reads
    /// `bricks` (sorted, no repeats): each is made resident and current,
    /// evicting bricks the level does not read when the bound is reached.
    pub fn update(
        &mut self,
        context: &GpuContext,
        mesh: &LightMesh,
        bricks: &[IVec3],
        point_to_node_tests: bool,
    ) -> Result<PoolUpload, RenderError> {
        let store = mesh.masks();
        if store.id() != self.store || store.words() != self.words {
            self.empty(store);
        }
        self.updates += 1;
        let slot_bytes = Self::slot_bytes(self.words);
        let binding = context.limits.max_storage_buffer_binding_size as usize;
        let limit_slots = self.limit.min(binding) / slot_bytes;
        if bricks.len() > limit_slots {
            let mib = |bytes: usize| bytes as f64 / f64::from(1 << 20);
            return Err(RenderError::LightMesh(LightMeshError::PoolTooSmall {
                needed_mib: mib(bricks.len() * slot_bytes),
                limit_mib: mib(self.limit),
                h: mesh.lattice.h,
            }));
        }
        let missing = bricks
            .iter()
            .filter(|brick| !self.resident.contains_key(brick))
            .count();
        let mut upload = PoolUpload {
            evicted: self.make_room(missing, limit_slots, bricks),
            ..PoolUpload::default()
        };
        let wanted = (self.allocated + missing.saturating_sub(self.free.len())).min(limit_slots);
        if wanted > self.capacity {
            self.grow(context, wanted.max(2 * self.capacity).min(limit_slots))?;
        }
        for &brick in bricks {
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
                    self.resident.entry(brick).or_insert(Resident {
                        slot,
                        revision: u64::MAX,
                        used: 0,
                    })
                }
            };
            resident.used = self.updates;
            if resident.revision != revision {
                resident.revision = revision;
                let offset = resident.slot as u64 * slot_bytes as u64;
                write_slot(context, &self.slots, offset, store, brick);
                upload.bricks += 1;
            }
        }
        let header = MeshHeader {
            origin: mesh.lattice.origin.to_array(),
            h: mesh.lattice.h,
            radius: mesh.radius(),
            words: self.words as u32,
            entry_mask: 0,
            point_to_node_tests: point_to_node_tests as u32,
        };
        self.build_directory(context, header)?;
        Ok(upload)
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
        self.words = store.words();
        self.resident.clear();
        self.free.clear();
        self.allocated = 0;
        self.capacity = 0;
        self.directory_stale = true;
    }

    /// Frees slots for `missing` new bricks where the pool is at its
    /// bound, evicting the least recently read bricks that `reading` does
    /// not name; returns how many were evicted.
    fn make_room(&mut self, missing: usize, limit_slots: usize, reading: &[IVec3]) -> u64 {
        let available = self.free.len() + (limit_slots - self.allocated.min(limit_slots));
        if missing <= available {
            return 0;
        }
        let mut idle: Vec<(u64, [i32; 3])> = (self.resident.iter())
            .filter(|(brick, _)| {
                reading
                    .binary_search_by_key(&brick.to_array(), |b| b.to_array())
                    .is_err()
            })
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
        let slot_bytes = Self::slot_bytes(self.words);
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
        Ok(())
    }

    /// Rebuilds and uploads the directory where the resident set or the
    /// header changed.
    fn build_directory(
        &mut self,
        context: &GpuContext,
        header: MeshHeader,
    ) -> Result<(), GpuError> {
        let entries = (2 * self.resident.len()).next_power_of_two().max(16);
        let header = MeshHeader {
            entry_mask: entries as u32 - 1,
            ..header
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

/// Copies `brick`'s nodes and enclosure flags from `store` into the slot
/// at `offset`.
fn write_slot(
    context: &GpuContext,
    slots: &wgpu::Buffer,
    offset: u64,
    store: &MaskStore,
    brick: IVec3,
) {
    let Some(nodes) = store.brick(brick) else {
        return;
    };
    let BrickEnclosure { known, enclosed } = store.enclosure(brick);
    let mut bytes = Vec::with_capacity(size_of_val(nodes) + 2 * size_of_val(&known));
    bytes.extend_from_slice(bytemuck::cast_slice(nodes));
    bytes.extend_from_slice(bytemuck::cast_slice(&known));
    bytes.extend_from_slice(bytemuck::cast_slice(&enclosed));
    context.queue.write_buffer(slots, offset, &bytes);
}
