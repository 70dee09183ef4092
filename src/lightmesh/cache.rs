//! The disk cache of static-layer masks (ARCHITECTURE.md, "The light mesh"): the bits
//! that say whether the segment from a node to a light misses the *static*
//! geometry depend only on that geometry, the lattice and the light's
//! position, so a later run (or another worker rendering another frame
//! range) can load them instead of tracing them again. The dynamic layer
//! is never cached; LMM1's enclosure flags are, as said below.
//!
//! In the frame loop the sequence's light mesh (`persistent`) loads the
//! file when it is made (the first LMM frame), importing each current
//! light's bits into the mask store before the first fill, and saves at the
//! end of the run, merging with whatever another worker wrote meanwhile
//! (a run that found no static bit of its own writes nothing).
//! What is saved are the bits for each light where the last frame placed
//! it and where it stood when the light mesh was made (kept aside when the
//! light first moved away): the positions a later run of the same or a
//! later frame range starts from. Positions in between are not kept, so a light
//! moving every frame does not grow the file by a section per frame.
//!
//! A file is named by a 128-bit content hash ([`CacheKey`]) of the format
//! version, the lattice (origin and `h`, bit-exact) and the static geometry
//! as the world's static structure is built from it, so any change to them
//! names another file. Inside, sections are keyed by light *position* (or
//! direction, for directional lights), not by index: lights move, and a
//! light that comes back to a position finds its bits.
//!
//! Layout, all little-endian:
//!
//! ```text
//! header  magic "LMMASKS\0" · version u32 · key u128 · sections u32
//!         · body length u64 · body checksum u64 (XXH3-64 of the body)
//! body    per section, in ascending order of light keys: kind u8
//!         (0 point/spot position, 1 direction) · 3 × f32 bits as u32
//!         · bricks u32 · the bricks, in ascending order, each with its
//!           valid and visible words (one bit per node slot), written as
//!           `super::brick_codec` says against the section before
//!         then LMM1's enclosure flags: the probes' reach as f32 bits
//!         · bricks u32 · the bricks, their known and enclosed words
//!           written as valid and visible ones, against no section
//! ```
//!
//! The enclosure flags (`super::enclosure`) depend on the static geometry,
//! the lattice and the probes' reach alone, so a run whose reach (kI·h
//! times `enclosure::REACH_IN_RADII`) is the file's takes them for the
//! bricks it imported bits into, and its first frame probes only nodes
//! the file did not have. A change to how probes decide must bump
//! [`FORMAT_VERSION`].
//!
//! A file that fails any check (magic, version, key, length, checksum,
//! structure) is reported with `log::warn!` and ignored: a wrong static bit
//! would be a wrong shadow in every frame, so nothing unverified is used.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{Affine3A, IVec3, Vec3};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

use super::brick_codec::{self, Bricks, Malformed, Reader};
use super::lattice::Lattice;
use super::masks::{BrickEnclosure, BrickLightBits, MaskStore, BRICK_WORDS};
use super::LightMesh;
use crate::output::{write_atomically, OutputError};
use crate::render::light::{LightSource, RenderLight};

/// Bumped whenever the layout or the meaning of a bit changes; it is both
/// in the header and in the key, so an old file is simply another name.
pub const FORMAT_VERSION: u32 = 3;

const MAGIC: [u8; 8] = *b"LMMASKS\0";
const HEADER_BYTES: usize = 8 + 4 + 16 + 4 + 8 + 8;
/// A lock file older than this was left by a worker that died while
/// saving (a save takes well under a second per hundred MB) and is
/// removed; a saver that still has no lock after twice this writes anyway.
const STALE_LOCK: Duration = Duration::from_secs(60);

/// Why a cache file was not used.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("cannot read: {0}")]
    Read(#[from] std::io::Error),
    #[error("{0} bytes is too short for a light-mesh cache header")]
    TooShort(usize),
    #[error("not a light-mesh cache file (wrong magic bytes)")]
    Magic,
    #[error("format version {found}, this build reads {FORMAT_VERSION}")]
    Version { found: u32 },
    #[error("written for another scene or lattice (key {found:032x})")]
    ForeignKey { found: u128 },
    #[error("the body is {found} bytes, the header says {expected} (truncated?)")]
    Length { expected: u64, found: usize },
    #[error("the body's checksum does not match (corrupt)")]
    Checksum,
    #[error("malformed body: {0}")]
    Malformed(&'static str),
}

/// Content hash naming a cache file: format version, lattice, static
/// geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CacheKey(pub u128);

impl From<Malformed> for CacheError {
    fn from(Malformed(what): Malformed) -> CacheError {
        CacheError::Malformed(what)
    }
}

impl CacheKey {
    /// The key of `geometry` (from [`static_geometry_hash`]) on `lattice`.
    pub fn new(geometry: u128, lattice: &Lattice) -> CacheKey {
        let mut hasher = Xxh3::new();
        hasher.update(b"lmanim light-mesh static masks");
        hasher.update(&FORMAT_VERSION.to_le_bytes());
        hash_vec3(&mut hasher, lattice.origin);
        hasher.update(&lattice.h.to_bits().to_le_bytes());
        hasher.update(&geometry.to_le_bytes());
        CacheKey(hasher.digest128())
    }

    /// The file for this key in `dir`.
    pub fn path_in(&self, dir: &Path) -> PathBuf {
        dir.join(format!("{:032x}.lmcache", self.0))
    }
}

/// Hash of the static objects exactly as the world's static structure is
/// built from them: per object (index, object-space positions, triangles,
/// render-space transform), bit-exact. Hashing the world's inputs rather
/// than transformed positions ties the key to what is traced, with no
/// second transform that could round differently.
pub fn static_geometry_hash<'a>(
    objects: impl IntoIterator<Item = (usize, &'a [Vec3], &'a [[u32; 3]], Affine3A)>,
) -> u128 {
    let mut hasher = Xxh3::new();
    for (index, positions, triangles, to_render) in objects {
        hasher.update(&(index as u64).to_le_bytes());
        hasher.update(&(positions.len() as u64).to_le_bytes());
        for &p in positions {
            hash_vec3(&mut hasher, p);
        }
        hasher.update(&(triangles.len() as u64).to_le_bytes());
        for triangle in triangles {
            for vertex in triangle {
                hasher.update(&vertex.to_le_bytes());
            }
        }
        for value in to_render.to_cols_array() {
            hasher.update(&value.to_bits().to_le_bytes());
        }
    }
    hasher.digest128()
}

fn hash_vec3(hasher: &mut Xxh3, v: Vec3) {
    for value in v.to_array() {
        hasher.update(&value.to_bits().to_le_bytes());
    }
}

/// What a light's static bits depend on: where its shadow segments end.
/// Point and spot lights share a kind (their shadow rays are the same);
/// a directional light is keyed by its direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct LightKey {
    directional: bool,
    bits: [u32; 3],
}

impl LightKey {
    pub fn of(light: &RenderLight) -> LightKey {
        let (directional, v) = match light.source {
            LightSource::Point { position } | LightSource::Spot { position, .. } => {
                (false, position)
            }
            LightSource::Directional { towards } => (true, towards),
        };
        LightKey {
            directional,
            bits: v.to_array().map(f32::to_bits),
        }
    }
}

/// Static-layer bits by light key and brick, and enclosure flags by
/// brick: the content of a cache file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StaticMaskCache {
    sections: BTreeMap<LightKey, Bricks>,
    enclosure: EnclosureFlags,
}

/// LMM1's enclosure flags by brick, with the bits of the probes' reach
/// they were settled with; no brick where none is known.
#[derive(Clone, Debug, Default, PartialEq)]
struct EnclosureFlags {
    reach: u32,
    bricks: Bricks,
}

impl EnclosureFlags {
    /// The flags a brick holds, as [`brick_codec`] stores a pair of words
    /// whose second lies within the first: known as valid, enclosed as
    /// visible.
    fn as_bits(flags: &BrickEnclosure) -> BrickLightBits {
        BrickLightBits {
            valid: flags.known,
            visible: flags.enclosed,
        }
    }

    fn of_bits(bits: &BrickLightBits) -> BrickEnclosure {
        BrickEnclosure {
            known: bits.valid,
            enclosed: bits.visible,
        }
    }

    /// ORs `other` in where it was settled with the same reach; flags of
    /// another reach are not these flags, and `self`'s stand (unless
    /// `self` holds none: then `other`'s are all there is).
    fn merge(&mut self, other: EnclosureFlags) {
        if self.bricks.is_empty() {
            *self = other;
        } else if other.reach == self.reach {
            for (brick, bits) in other.bricks {
                merge_brick(&mut self.bricks, brick, &bits);
            }
        }
    }
}

impl StaticMaskCache {
    /// The static bits `store` holds for each of `lights` (at its current
    /// position).
    pub fn from_store(store: &MaskStore, lights: &[RenderLight]) -> StaticMaskCache {
        let mut cache = StaticMaskCache::default();
        cache.add_lights(store, lights, 0..lights.len());
        cache
    }

    /// ORs in the static bits `store` holds for the lights numbered
    /// `which`, each standing at its position in `lights`.
    pub fn add_lights(
        &mut self,
        store: &MaskStore,
        lights: &[RenderLight],
        which: impl IntoIterator<Item = usize>,
    ) {
        let mut wanted = vec![0u64; store.words()];
        for index in which {
            wanted[index / 64] |= 1 << (index % 64);
        }
        let keys: Vec<LightKey> = lights.iter().map(LightKey::of).collect();
        store.for_each_static_brick(&wanted, |brick, index, bits| {
            let section = self.sections.entry(keys[index]).or_default();
            merge_brick(section, brick.to_array(), bits);
        });
    }

    /// Takes the enclosure flags `store` has, settled with the probes'
    /// `reach`.
    pub fn add_enclosure(&mut self, store: &MaskStore, reach: f32) {
        let bricks = (store.known_enclosures())
            .map(|(brick, flags)| (brick.to_array(), EnclosureFlags::as_bits(flags)))
            .collect();
        self.enclosure.merge(EnclosureFlags {
            reach: reach.to_bits(),
            bricks,
        });
    }

    /// ORs `other` in. Static bits and enclosure flags are functions of
    /// the key (and the reach), so two workers' files cannot disagree
    /// where both have a bit.
    pub fn merge(&mut self, other: StaticMaskCache) {
        for (light, bricks) in other.sections {
            let section = self.sections.entry(light).or_default();
            for (brick, bits) in bricks {
                merge_brick(section, brick, &bits);
            }
        }
        self.enclosure.merge(other.enclosure);
    }

    /// Whether it holds no section and no enclosure flag.
    pub fn is_empty(&self) -> bool {
        self.sections.is_empty() && self.enclosure.bricks.is_empty()
    }

    /// Valid static bits held, over all sections.
    pub fn bits(&self) -> u64 {
        self.sections
            .values()
            .flat_map(|bricks| bricks.values())
            .map(|bits| {
                bits.valid
                    .iter()
                    .map(|w| w.count_ones() as u64)
                    .sum::<u64>()
            })
            .sum()
    }

    /// Imports the enclosure flags settled with the probes' `reach` into
    /// the bricks `store` has (those the import of bits made, or earlier
    /// frames); returns the flags the store did not know.
    pub fn import_enclosure(&self, store: &mut MaskStore, reach: f32) -> u64 {
        if self.enclosure.reach != reach.to_bits() {
            return 0;
        }
        (self.enclosure.bricks.iter())
            .map(|(&brick, bits)| {
                store.import_enclosure(IVec3::from_array(brick), &EnclosureFlags::of_bits(bits))
            })
            .sum()
    }

    /// Imports the bits of every light of `lights` whose position has a
    /// section into `store`, creating at most `max_bricks` bricks in all;
    /// returns the bits imported.
    pub fn import(&self, store: &mut MaskStore, lights: &[RenderLight], max_bricks: usize) -> u64 {
        // Brick by brick, every light's bits while the brick's nodes are
        // in the processor's cache (a file holds them light by light).
        let mut by_brick: Vec<([i32; 3], usize, &BrickLightBits)> = (lights.iter().enumerate())
            .filter_map(|(index, light)| Some((index, self.sections.get(&LightKey::of(light))?)))
            .flat_map(|(index, bricks)| {
                bricks
                    .iter()
                    .map(move |(&brick, bits)| (brick, index, bits))
            })
            .collect();
        by_brick.sort_unstable_by_key(|&(brick, index, _)| (brick, index));
        let mut imported = 0;
        let mut brick_lights = Vec::new();
        for entries in by_brick.chunk_by(|a, b| a.0 == b.0) {
            let brick = IVec3::from_array(entries[0].0);
            if store.has_brick(brick) || store.brick_count() < max_bricks {
                brick_lights.clear();
                brick_lights.extend(entries.iter().map(|&(_, index, bits)| (index, bits)));
                imported += store.import_static(brick, &brick_lights);
            }
        }
        imported
    }

    /// The file's bytes for `key`, the body's length and checksum
    /// written into the header last.
    pub fn encode(&self, key: CacheKey) -> Vec<u8> {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(&MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&key.0.to_le_bytes());
        bytes.extend_from_slice(&(self.sections.len() as u32).to_le_bytes());
        let length_at = bytes.len();
        bytes.extend_from_slice(&[0; 16]);
        let mut previous = None;
        for (light, bricks) in &self.sections {
            bytes.push(light.directional as u8);
            for value in light.bits {
                bytes.extend_from_slice(&value.to_le_bytes());
            }
            bytes.extend_from_slice(&(bricks.len() as u32).to_le_bytes());
            brick_codec::encode(bricks, previous, &mut bytes);
            previous = Some(bricks);
        }
        let flags = &self.enclosure;
        bytes.extend_from_slice(&flags.reach.to_le_bytes());
        bytes.extend_from_slice(&(flags.bricks.len() as u32).to_le_bytes());
        brick_codec::encode(&flags.bricks, None, &mut bytes);
        let body = &bytes[HEADER_BYTES..];
        let (length, checksum) = (body.len() as u64, xxh3_64(body));
        bytes[length_at..length_at + 8].copy_from_slice(&length.to_le_bytes());
        bytes[length_at + 8..HEADER_BYTES].copy_from_slice(&checksum.to_le_bytes());
        bytes
    }

    /// Parses and verifies a file's bytes, which must have been written
    /// for `key`.
    pub fn decode(bytes: &[u8], key: CacheKey) -> Result<StaticMaskCache, CacheError> {
        if bytes.len() < HEADER_BYTES {
            return Err(CacheError::TooShort(bytes.len()));
        }
        let mut header = Reader::new(bytes);
        if header.take(8)? != MAGIC {
            return Err(CacheError::Magic);
        }
        let version = header.u32()?;
        if version != FORMAT_VERSION {
            return Err(CacheError::Version { found: version });
        }
        let found = u128::from_le_bytes(header.array()?);
        if found != key.0 {
            return Err(CacheError::ForeignKey { found });
        }
        let sections = header.u32()?;
        let body_len = header.u64()?;
        let checksum = header.u64()?;
        let body = &bytes[HEADER_BYTES..];
        if body.len() as u64 != body_len {
            return Err(CacheError::Length {
                expected: body_len,
                found: body.len(),
            });
        }
        if xxh3_64(body) != checksum {
            return Err(CacheError::Checksum);
        }

        let mut reader = Reader::new(body);
        let mut cache = StaticMaskCache::default();
        let mut previous: Option<LightKey> = None;
        for _ in 0..sections {
            let directional = match reader.u8()? {
                0 => false,
                1 => true,
                _ => return Err(CacheError::Malformed("unknown light kind")),
            };
            let light = LightKey {
                directional,
                bits: [reader.u32()?, reader.u32()?, reader.u32()?],
            };
            if previous.is_some_and(|previous| previous >= light) {
                return Err(CacheError::Malformed("sections out of order"));
            }
            let count = reader.u32()? as usize;
            let before = previous.and_then(|previous| cache.sections.get(&previous));
            let bricks = brick_codec::decode(&mut reader, count, before)?;
            cache.sections.insert(light, bricks);
            previous = Some(light);
        }
        let reach = reader.u32()?;
        let count = reader.u32()? as usize;
        let bricks = brick_codec::decode(&mut reader, count, None)?;
        cache.enclosure = EnclosureFlags { reach, bricks };
        if reader.remaining() != 0 {
            return Err(CacheError::Malformed("bytes after the last section"));
        }
        Ok(cache)
    }

    /// The cache in `dir` for `key`: None when there is no file, or (with
    /// a warning) when it cannot be read or fails verification.
    pub fn load(dir: &Path, key: CacheKey) -> Option<StaticMaskCache> {
        let path = key.path_in(dir);
        let bytes = match std::fs::read(&path) {
            Ok(bytes) => bytes,
            Err(error) if error.kind() == std::io::ErrorKind::NotFound => return None,
            Err(error) => {
                log::warn!("{}: {}; ignored", path.display(), CacheError::from(error));
                return None;
            }
        };
        match StaticMaskCache::decode(&bytes, key) {
            Ok(cache) => Some(cache),
            Err(error) => {
                log::warn!("{}: {error}; ignored", path.display());
                None
            }
        }
    }

    /// Writes the cache to `dir` for `key`, merged with the file already
    /// there (another worker's), atomically. Savers of one key take turns
    /// through a lock file so that neither loses the other's bits; a lock
    /// older than a minute is taken over. Writing without the lock
    /// (when it cannot be had) can lose bits, which later runs recompute,
    /// but never leaves a torn file.
    pub fn save(mut self, dir: &Path, key: CacheKey) -> Result<(), OutputError> {
        let path = key.path_in(dir);
        std::fs::create_dir_all(dir).map_err(|source| OutputError::CreateDir {
            path: dir.to_path_buf(),
            source,
        })?;
        let _lock = SaveLock::acquire(&path);
        if let Some(existing) = StaticMaskCache::load(dir, key) {
            self.merge(existing);
        }
        let bytes = self.encode(key);
        write_atomically(&path, |writer| {
            writer
                .write_all(&bytes)
                .map_err(|source| OutputError::Write {
                    path: path.clone(),
                    source,
                })
        })
    }
}

fn merge_brick(section: &mut Bricks, brick: [i32; 3], bits: &BrickLightBits) {
    let stored = section.entry(brick).or_default();
    for word in 0..BRICK_WORDS {
        stored.visible[word] |= bits.visible[word];
        stored.valid[word] |= bits.valid[word];
    }
}

/// A lock file beside the cache file, held while reading, merging and
/// writing; removed when dropped.
struct SaveLock(Option<PathBuf>);

impl SaveLock {
    fn acquire(target: &Path) -> SaveLock {
        let mut name = target.as_os_str().to_owned();
        name.push(".lock");
        let lock = PathBuf::from(name);
        let started = Instant::now();
        loop {
            match File::create_new(&lock) {
                Ok(_) => return SaveLock(Some(lock)),
                Err(error) if error.kind() == std::io::ErrorKind::AlreadyExists => {
                    if started.elapsed() > 2 * STALE_LOCK {
                        log::warn!(
                            "{}: still locked after {} s; writing without the lock",
                            lock.display(),
                            started.elapsed().as_secs()
                        );
                        return SaveLock(None);
                    }
                    let age = std::fs::metadata(&lock)
                        .and_then(|meta| meta.modified())
                        .ok()
                        .and_then(|modified| modified.elapsed().ok());
                    if age.is_some_and(|age| age > STALE_LOCK) {
                        log::warn!("{}: stale lock removed", lock.display());
                        // Another saver may remove it first; either way the
                        // next attempt decides who holds it.
                        let _ = std::fs::remove_file(&lock);
                        continue;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
                Err(error) => {
                    log::warn!("{}: {error}; writing without the lock", lock.display());
                    return SaveLock(None);
                }
            }
        }
    }
}

impl Drop for SaveLock {
    fn drop(&mut self) {
        if let Some(lock) = &self.0 {
            // A lock that cannot be removed only makes later savers wait.
            let _ = std::fs::remove_file(lock);
        }
    }
}

impl LightMesh {
    /// Imports the static bits that `dir` holds for this lattice, the
    /// static geometry hashed as `geometry`, and `lights` at their current
    /// positions; returns the bits imported. The store may grow to half its
    /// memory limit this way, leaving the rest to the frames.
    pub fn load_static_masks(&mut self, dir: &Path, geometry: u128, lights: &[RenderLight]) -> u64 {
        let key = CacheKey::new(geometry, &self.lattice);
        let Some(cache) = StaticMaskCache::load(dir, key) else {
            return 0;
        };
        let max_bricks = self.memory_limit / 2 / MaskStore::brick_bytes(lights.len());
        let imported = cache.import(&mut self.masks, lights, max_bricks);
        let reach = self.probe_reach();
        cache.import_enclosure(&mut self.masks, reach);
        imported
    }

    /// Copies the static bits of the lights `moved` into `kept` before
    /// invalidation drops them; `lights` says where they stood.
    pub fn keep_static_masks(
        &self,
        kept: &mut StaticMaskCache,
        lights: &[RenderLight],
        moved: impl IntoIterator<Item = usize>,
    ) {
        kept.add_lights(&self.masks, lights, moved);
    }

    /// Saves the static bits of `lights` (at their current positions),
    /// those `kept` from earlier positions and the enclosure flags to
    /// `dir`, merged with the file there. Where the run found no static
    /// bit and no flag and kept none, everything the store holds came from
    /// that file, and nothing is written: a warm run does not rewrite (and
    /// first re-read) a file of tens of megabytes to add nothing.
    pub fn save_static_masks(
        &self,
        dir: &Path,
        geometry: u128,
        lights: &[RenderLight],
        kept: &StaticMaskCache,
    ) -> Result<(), OutputError> {
        let found = self.masks.static_bits_found() + self.masks.enclosure_flags_found();
        if found == 0 && kept.is_empty() {
            return Ok(());
        }
        let key = CacheKey::new(geometry, &self.lattice);
        let mut cache = StaticMaskCache::from_store(&self.masks, lights);
        cache.add_enclosure(&self.masks, self.probe_reach());
        cache.merge(kept.clone());
        cache.save(dir, key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lightmesh::masks::split;

    fn point(position: Vec3) -> RenderLight {
        RenderLight {
            source: LightSource::Point { position },
            power: Vec3::ONE,
            range: None,
            lamp_radius: 0.1,
        }
    }

    fn sample() -> (StaticMaskCache, Vec<RenderLight>) {
        let lights = vec![
            point(Vec3::new(0.0, 5.0, 0.0)),
            point(Vec3::new(3.0, 5.0, 1.0)),
        ];
        let mut store = MaskStore::new(lights.len());
        store.set(IVec3::new(-9, 2, 17), 0, true, Some(true));
        store.set(IVec3::new(-9, 2, 18), 0, false, None);
        store.set(IVec3::new(40, -3, 0), 1, true, None);
        (StaticMaskCache::from_store(&store, &lights), lights)
    }

    #[test]
    fn encoding_round_trips_and_imports_static_bits_only() {
        let (cache, lights) = sample();
        assert_eq!(cache.bits(), 3);
        let key = CacheKey(0x1234);
        let decoded = StaticMaskCache::decode(&cache.encode(key), key).unwrap();
        assert_eq!(decoded, cache);

        // The lights swapped places: sections follow positions.
        let swapped = vec![lights[1], lights[0]];
        let mut store = MaskStore::new(2);
        assert_eq!(decoded.import(&mut store, &swapped, usize::MAX), 3);
        let node = store.node(IVec3::new(-9, 2, 17)).unwrap();
        assert_eq!(node.static_layer(0), (0b10, 0b10));
        assert_eq!(
            node.dynamic_layer(0),
            (0, 0),
            "the dynamic layer is not cached"
        );
        assert_eq!(store.get(IVec3::new(-9, 2, 18), 1), Some(false));
        assert_eq!(store.get(IVec3::new(40, -3, 0), 0), None, "statically open");
        assert_eq!(store.nodes_cached(), 3);
        assert_eq!(store.static_bits(), 3);
    }

    #[test]
    fn enclosure_flags_round_trip_and_keep_to_their_reach() {
        let (mut cache, lights) = sample();
        let mut store = MaskStore::new(lights.len());
        store.set(IVec3::new(-9, 2, 17), 0, true, None);
        let brick = split(IVec3::new(-9, 2, 17)).0;
        let flags = BrickEnclosure {
            known: [0b111, 0, 0, 0, 0, 0, 0, 1 << 63],
            enclosed: [0b101, 0, 0, 0, 0, 0, 0, 0],
        };
        store.merge_enclosure(brick, &flags);
        assert_eq!(store.enclosure_flags_found(), 4);
        cache.add_enclosure(&store, 1.5);
        let key = CacheKey(3);
        let decoded = StaticMaskCache::decode(&cache.encode(key), key).unwrap();
        assert_eq!(decoded, cache);

        // Into a store holding the brick, at the same reach only; imports
        // are not flags found.
        let mut into = MaskStore::new(lights.len());
        assert_eq!(decoded.import(&mut into, &lights, usize::MAX), 3);
        assert_eq!(decoded.import_enclosure(&mut into, 2.0), 0);
        assert_eq!(into.enclosure(brick), BrickEnclosure::default());
        assert_eq!(decoded.import_enclosure(&mut into, 1.5), 4);
        assert_eq!(into.enclosure(brick), flags);
        assert_eq!(into.enclosure_flags_found(), 0);
        assert_eq!(
            decoded.import_enclosure(&mut MaskStore::new(2), 1.5),
            0,
            "no brick made"
        );

        // A file's flags of another reach do not mix with the run's.
        let mut other = StaticMaskCache::default();
        let mut elsewhere = MaskStore::new(2);
        elsewhere.merge_enclosure(IVec3::new(5, 5, 5), &flags);
        other.add_enclosure(&elsewhere, 2.0);
        let mut merged = cache.clone();
        merged.merge(other);
        assert_eq!(merged, cache);
    }

    #[test]
    fn import_creates_no_brick_past_the_limit() {
        let (cache, lights) = sample();
        let mut store = MaskStore::new(2);
        assert_eq!(cache.import(&mut store, &lights, 0), 0);
        assert_eq!(store.brick_count(), 0);
        // Nodes (-9, 2, 17) and (-9, 2, 18) share a brick; (40, -3, 0) not.
        assert_eq!(cache.import(&mut store, &lights, 1), 2);
        assert_eq!(store.brick_count(), 1);
    }

    #[test]
    fn damaged_or_foreign_bytes_are_refused() {
        let (cache, _) = sample();
        let key = CacheKey(7);
        let bytes = cache.encode(key);
        let refuse = |bytes: &[u8]| StaticMaskCache::decode(bytes, key).unwrap_err();
        assert!(matches!(refuse(&[]), CacheError::TooShort(0)));
        assert!(matches!(
            refuse(&bytes[..bytes.len() - 1]),
            CacheError::Length { .. }
        ));
        let mut flipped = bytes.clone();
        flipped[HEADER_BYTES + 20] ^= 0x10;
        assert!(matches!(refuse(&flipped), CacheError::Checksum));
        let mut magic = bytes.clone();
        magic[0] = b'X';
        assert!(matches!(refuse(&magic), CacheError::Magic));
        let mut version = bytes.clone();
        version[8] = 99;
        assert!(matches!(
            refuse(&version),
            CacheError::Version { found: 99 }
        ));
        assert!(matches!(
            StaticMaskCache::decode(&bytes, CacheKey(8)).unwrap_err(),
            CacheError::ForeignKey { found: 7 }
        ));
    }

    #[test]
    fn keys_change_with_the_lattice_and_the_geometry() {
        let triangles = [[0, 1, 2]];
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let moved = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 1e-6)];
        let geometry = |positions: &[Vec3]| {
            static_geometry_hash([(0, positions, &triangles[..], Affine3A::IDENTITY)])
        };
        let lattice = Lattice::new(0.25);
        let key = CacheKey::new(geometry(&positions), &lattice);
        assert_eq!(key, CacheKey::new(geometry(&positions), &lattice));
        assert_ne!(key, CacheKey::new(geometry(&moved), &lattice));
        assert_ne!(
            key,
            CacheKey::new(geometry(&positions), &Lattice::new(0.26))
        );
    }
}
