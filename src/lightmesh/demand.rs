//! Stage 3 of an LMM frame, node demand: for every shading point, the lights
//! that can reach it and the nodes of its half-ball (steps 1–2), gathered
//! into per-brick tables of the light bits some point needs at each node.
//! Neighbouring points share most of their nodes; OR-ing into a brick-shaped
//! table merges them without sorting millions of entries.

use glam::IVec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::faint::LampTerms;
use super::lattice::Row;
use super::masks::{parity, split, BRICK_NODES};
use super::wide_ball::{self, WideBall};
use super::{LightMesh, LightMeshError};
use crate::render::omega::{LightLanes, PointLanes, LANES};
use crate::render::surface::ShadingPoint;

/// Light bits needed at each node of one brick: `needed[slot * words + w]`
/// holds lights `64·w ..` of the node in `slot`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BrickDemand {
    pub brick: IVec3,
    pub needed: Box<[u64]>,
}

/// What one frame's shading points need of the light mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Demand {
    /// Bricks sorted by coordinates.
    pub bricks: Vec<BrickDemand>,
    /// Per point, `words` words: bit i set when light i can reach it (what
    /// shading will ask formula (2) for).
    pub reach: Vec<u64>,
    /// Per point, `words` words: its faint lamps (`super::faint`), whose
    /// penumbrae keep the half-ball's answer and whose wide set is not
    /// demanded. Found once here, for demand and shading both.
    pub faint: Vec<u64>,
    pub words: usize,
}

impl Demand {
    /// The reaching lights and the faint lamps of point `index`.
    pub fn of_point(&self, index: usize) -> (&[u64], &[u64]) {
        let words = index * self.words..(index + 1) * self.words;
        (&self.reach[words.clone()], &self.faint[words])
    }
}

/// Points per parallel chunk: large enough that neighbours share nodes.
const CHUNK: usize = 4096;

/// Brick tables under construction, with the bricks touched last cached
/// by the parity of their coordinates (a half-ball spans at most 2×2×2
/// bricks, and consecutive points share them), as in
/// [`super::masks::BrickCache`].
struct BrickTables {
    words: usize,
    index: FxHashMap<IVec3, usize>,
    bricks: Vec<BrickDemand>,
    recent: [Option<(IVec3, usize)>; 8],
}

impl BrickTables {
    fn new(words: usize) -> BrickTables {
        BrickTables {
            words,
            index: FxHashMap::default(),
            bricks: Vec::new(),
            recent: [None; 8],
        }
    }

    fn table(&mut self, brick: IVec3) -> &mut [u64] {
        let position = self.position(brick);
        &mut self.bricks[position].needed
    }

    /// Where `brick`'s table is in `bricks`, made first if need be.
    fn position(&mut self, brick: IVec3) -> usize {
        let entry = parity(brick);
        match self.recent[entry] {
            Some((recent, position)) if recent == brick => position,
            _ => {
                let words = self.words;
                let bricks = &mut self.bricks;
                let position = *self.index.entry(brick).or_insert_with(|| {
                    bricks.push(BrickDemand {
                        brick,
                        needed: vec![0; BRICK_NODES * words].into_boxed_slice(),
                    });
                    bricks.len() - 1
                });
                self.recent[entry] = Some((brick, position));
                position
            }
        }
    }

    /// Needs `lights` at the nodes of `row`, a row of the lattice whose
    /// node i is the mesh's i·`steps`: its brick looked up once, and again
    /// only where the row crosses into the next.
    fn need_row(&mut self, row: Row, steps: i32, lights: &[u64]) {
        let words = self.words;
        let mut current: Option<(IVec3, usize)> = None;
        for node in row.nodes() {
            let (brick, slot) = split(node * steps);
            let position = match current {
                Some((at, position)) if at == brick => position,
                _ => self.position(brick),
            };
            current = Some((brick, position));
            let needed = &mut self.bricks[position].needed[slot * words..(slot + 1) * words];
            for (into, &bits) in needed.iter_mut().zip(lights) {
                *into |= bits;
            }
        }
    }

    fn absorb(&mut self, other: BrickTables) {
        for brick in other.bricks {
            let table = self.table(brick.brick);
            for (into, from) in table.iter_mut().zip(brick.needed.iter()) {
                *into |= from;
            }
        }
    }
}

/// One kind of walk (the half-ball, or the wide set) from point to point,
/// its nodes gathered over consecutive points that need the same lights
/// and asked of the tables once: neighbouring points' sets overlap mostly
/// (on the 64-lamp street at 1080p, the two walks visited 89 M nodes for
/// 1.2 M distinct ones), and the tables only OR, so a node asked once for the
/// lights of several points is asked exactly what each would have asked.
/// Points with other lights start a new gathering, so no node is ever
/// asked for a light a point of its own did not need.
struct Walk {
    /// Mesh steps per step of the walk's lattice.
    steps: i32,
    rows: Vec<Row>,
    gathered: Windows,
    /// The lights the gathered nodes are needed for.
    lights: Vec<u64>,
}

impl Walk {
    fn new(steps: i32, words: usize) -> Walk {
        Walk {
            steps,
            rows: Vec::new(),
            gathered: Windows::new(),
            lights: vec![0; words],
        }
    }

    /// The point's rows go here.
    fn start(&mut self) -> &mut Vec<Row> {
        self.rows.clear();
        &mut self.rows
    }

    /// Needs `lights` at the nodes walked: gathered with the previous
    /// points' where they need the same lights, asked of the tables when
    /// the lights change or the gathering is full.
    fn need(&mut self, tables: &mut BrickTables, lights: &[u64]) {
        if self.lights != lights {
            self.flush(tables);
            self.lights.copy_from_slice(lights);
        }
        for index in 0..self.rows.len() {
            if self.gathered.is_full() {
                self.flush(tables);
            }
            self.gathered.add(self.rows[index]);
        }
    }

    /// Asks the tables for what is gathered, and starts again: at a change
    /// of lights, when the gathering is full, and after the chunk's last
    /// point.
    fn flush(&mut self, tables: &mut BrickTables) {
        for row in self.gathered.drain() {
            tables.need_row(row, self.steps, &self.lights);
        }
    }
}

/// A set of lattice nodes as rows along x aligned to multiples of eight
/// (a node at x = 8·k + i is bit i of window k), in an open-addressed
/// table that is emptied, never grown: a row of the walks' is at most two
/// windows, and OR-ing its lanes into them is the union.
struct Windows {
    /// Per slot, the window's first node; meaningful where `lanes` ≠ 0.
    firsts: Box<[IVec3]>,
    lanes: Box<[u8]>,
    /// The slots in use, in the order they were taken.
    used: Vec<u16>,
}

impl Windows {
    const SLOT_BITS: u32 = 9;
    const SLOTS: usize = 1 << Self::SLOT_BITS;
    /// Windows held before the set asks to be emptied (checked before
    /// each row, which adds at most two): a quarter of the slots, so a
    /// probe seldom goes past one or two.
    const FULL: usize = Self::SLOTS / 4;

    fn new() -> Windows {
        Windows {
            firsts: vec![IVec3::ZERO; Self::SLOTS].into_boxed_slice(),
            lanes: vec![0; Self::SLOTS].into_boxed_slice(),
            used: Vec::with_capacity(Self::FULL + 2),
        }
    }

    fn add(&mut self, row: Row) {
        let offset = row.first.x.rem_euclid(8);
        let first = IVec3::new(row.first.x - offset, row.first.y, row.first.z);
        let lanes = u16::from(row.lanes) << offset;
        self.or(first, lanes as u8);
        self.or(first + IVec3::X * 8, (lanes >> 8) as u8);
    }

    fn or(&mut self, first: IVec3, lanes: u8) {
        if lanes == 0 {
            return;
        }
        let mut slot = Self::slot_of(first);
        loop {
            match self.lanes[slot] {
                0 => {
                    self.firsts[slot] = first;
                    self.lanes[slot] = lanes;
                    self.used.push(slot as u16);
                    return;
                }
                _ if self.firsts[slot] == first => {
                    self.lanes[slot] |= lanes;
                    return;
                }
                _ => slot = (slot + 1) % Self::SLOTS,
            }
        }
    }

    fn slot_of(first: IVec3) -> usize {
        let key = (first.x as u32 as u64 >> 3)
            ^ (first.y as u32 as u64) << 21
            ^ (first.z as u32 as u64) << 42;
        (key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - Self::SLOT_BITS)) as usize
    }

    fn is_full(&self) -> bool {
        self.used.len() >= Self::FULL
    }

    /// The windows held, as rows, leaving the set empty.
    fn drain(&mut self) -> impl Iterator<Item = Row> + '_ {
        let (firsts, lanes) = (&self.firsts, &mut self.lanes);
        self.used.drain(..).map(move |slot| {
            let slot = slot as usize;
            let row = Row {
                first: firsts[slot],
                lanes: lanes[slot],
            };
            lanes[slot] = 0;
            row
        })
    }
}

impl LightMesh {
    /// What `points` need: reaching lights per point and needed bits per
    /// node, in bricks: each point's half-ball for its lights and, with
    /// `penumbra: wide`, its wide set for its lamps but the faint ones
    /// (`super::wide`, `super::faint`). The
    /// tables grow with the number of distinct bricks the points touch, so
    /// their size is checked against the memory limit as they grow: a
    /// lattice far too fine for the view is refused here, before it can
    /// exhaust memory.
    pub fn demand(
        &self,
        points: &[ShadingPoint],
        lights: &LightLanes,
    ) -> Result<Demand, LightMeshError> {
        let words = self.masks().words();
        let mut reach = vec![0; points.len() * words];
        let mut faint = vec![0; points.len() * words];
        let lamps = wide_ball::lamps(lights.lights(), words);
        let parts = self.faint_budget();
        // The lamps' terms are asked for only where some lamp can be faint.
        let termed = (parts != 0).then_some(&lamps[..]);
        (reach.par_chunks_mut(words))
            .zip(faint.par_chunks_mut(words))
            .zip(points)
            .for_each_init(
                || LampTerms::new(words),
                |terms, ((reach, faint), point)| {
                    reaching_lights(&PointLanes::new(point), lights, (reach, termed), terms);
                    terms.mark(parts, faint);
                },
            );

        let table_bytes = BRICK_NODES * words * std::mem::size_of::<u64>();
        let brick_limit = self.memory_limit / table_bytes;
        let too_large = |bricks: usize| self.too_large(bricks.saturating_mul(table_bytes));
        let wide = (self.penumbra.asks_wide_set()).then(|| WideBall::of(self));
        let tables = points
            .par_chunks(CHUNK)
            .zip(reach.par_chunks(CHUNK * words))
            .zip(faint.par_chunks(CHUNK * words))
            .try_fold(
                || BrickTables::new(words),
                |mut tables, ((chunk, chunk_reach), chunk_faint)| {
                    let mut half_ball = Walk::new(1, words);
                    let mut wide_set = Walk::new(wide_ball::STEPS, words);
                    let mut lamps_reached = vec![0; words];
                    let per_point = chunk_reach.chunks(words).zip(chunk_faint.chunks(words));
                    for (point, (point_reach, point_faint)) in chunk.iter().zip(per_point) {
                        if point_reach.iter().all(|&word| word == 0) {
                            continue;
                        }
                        let (p, n) = (point.position, point.geometric_normal);
                        let rows = half_ball.start();
                        self.lattice
                            .half_ball_rows(p, n, self.radius(), |row| rows.push(row));
                        half_ball.need(&mut tables, point_reach);
                        let Some(ball) = &wide else {
                            continue;
                        };
                        for (reached, ((&reach, &lamp), &faint)) in lamps_reached
                            .iter_mut()
                            .zip(point_reach.iter().zip(&lamps).zip(point_faint))
                        {
                            *reached = reach & lamp & !faint;
                        }
                        if lamps_reached.iter().all(|&word| word == 0) {
                            continue;
                        }
                        let rows = wide_set.start();
                        ball.rows(p, n, |row| rows.push(row));
                        wide_set.need(&mut tables, &lamps_reached);
                    }
                    half_ball.flush(&mut tables);
                    wide_set.flush(&mut tables);
                    match tables.bricks.len() {
                        count if count > brick_limit => Err(too_large(count)),
                        _ => Ok(tables),
                    }
                },
            )
            .try_reduce(
                || BrickTables::new(words),
                |mut a, b| {
                    a.absorb(b);
                    match a.bricks.len() {
                        count if count > brick_limit => Err(too_large(count)),
                        _ => Ok(a),
                    }
                },
            )?;
        let mut bricks = tables.bricks;
        bricks.par_sort_unstable_by_key(|brick| brick.brick.to_array());
        Ok(Demand {
            bricks,
            reach,
            faint,
            words,
        })
    }
}

/// Sets bit i of `reach` when light i can reach the point `at`, and
/// gathers into `terms` those of the lights among them that are `lamps`
/// (the same layout) where those are asked for: one arrival of each block
/// of lights serves both, the BRDF evaluated only for blocks with a lamp.
fn reaching_lights(
    at: &PointLanes,
    lights: &LightLanes,
    (reach, lamps): (&mut [u64], Option<&[u64]>),
    terms: &mut LampTerms,
) {
    reach.fill(0);
    terms.clear();
    for block in 0..lights.blocks() {
        let arrival = lights.arrival(at, block);
        let first = block * LANES;
        let (word, shift) = (first / 64, first % 64);
        let lanes = arrival.reaching();
        reach[word] |= u64::from(lanes) << shift;
        let lamp_lanes = lamps.map_or(0, |lamps| lanes & (lamps[word] >> shift) as u8);
        if lamp_lanes != 0 {
            terms.add(first, lamp_lanes, &arrival.omega(at));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The tables' bricks, sorted by coordinates.
    fn sorted(tables: BrickTables) -> Vec<BrickDemand> {
        let mut bricks = tables.bricks;
        bricks.sort_by_key(|brick| brick.brick.to_array());
        bricks
    }

    proptest! {
        /// Gathering points' rows before asking the tables gives the
        /// tables asking row by row gives: the same bricks, the same bits
        /// at every node, whatever the order of lights and rows, at
        /// negative coordinates, on the mesh's lattice and the wide
        /// set's, and through a gathering that fills up within a point.
        #[test]
        fn gathered_walks_need_what_each_point_needs(
            points in prop::collection::vec(
                (
                    prop::collection::vec(((-40i32..40, -3i32..3, -3i32..3), 1u8..), 0..300),
                    prop::sample::select(vec![[1u64, 0], [1, 0], [6, 0], [0, 1 << 63]]),
                ),
                1..12,
            ),
            steps in prop::sample::select(vec![1, wide_ball::STEPS]),
        ) {
            let words = 2;
            let mut row_by_row = BrickTables::new(words);
            let mut gathered = BrickTables::new(words);
            let mut walk = Walk::new(steps, words);
            for (rows, lights) in &points {
                let rows: Vec<Row> = (rows.iter())
                    .map(|&((x, y, z), lanes)| Row { first: IVec3::new(x, y, z), lanes })
                    .collect();
                for &row in &rows {
                    row_by_row.need_row(row, steps, lights);
                }
                walk.start().extend(&rows);
                walk.need(&mut gathered, lights);
            }
            walk.flush(&mut gathered);
            prop_assert_eq!(sorted(gathered), sorted(row_by_row));
        }
    }

    #[test]
    fn tables_or_the_needs_of_shared_nodes_together() {
        let node = |first: IVec3| Row { first, lanes: 1 };
        let mut a = BrickTables::new(2);
        a.need_row(node(IVec3::new(1, 2, 3)), 1, &[1, 0]);
        a.need_row(node(IVec3::new(-1, 0, 0)), 1, &[0, 4]);
        let mut b = BrickTables::new(2);
        b.need_row(node(IVec3::new(1, 2, 3)), 1, &[2, 8]);
        a.absorb(b);
        assert_eq!(a.bricks.len(), 2);
        let (brick, slot) = split(IVec3::new(1, 2, 3));
        let table = a.table(brick);
        assert_eq!(&table[slot * 2..slot * 2 + 2], &[3, 8]);
        let (brick, slot) = split(IVec3::new(-1, 0, 0));
        assert_eq!(&a.table(brick)[slot * 2..slot * 2 + 2], &[0, 4]);
    }

    /// A row's nodes land in the slots of their own bricks, for the
    /// mesh's lattice and the wide set's (every other mesh node), where
    /// the row crosses from brick to brick, at negative coordinates too.
    #[test]
    fn a_row_needs_exactly_its_nodes_across_bricks() {
        for steps in [1, wide_ball::STEPS] {
            let row = Row {
                first: IVec3::new(-5, 7, -9),
                lanes: 0b1011_0101,
            };
            let mut tables = BrickTables::new(1);
            tables.need_row(row, steps, &[0b110]);
            let wanted: Vec<IVec3> = row.nodes().map(|node| node * steps).collect();
            let mut needed = Vec::new();
            for brick in &tables.bricks {
                for (slot, &bits) in brick.needed.iter().enumerate() {
                    if bits != 0 {
                        assert_eq!(bits, 0b110);
                        needed.push(crate::lightmesh::masks::join(brick.brick, slot));
                    }
                }
            }
            needed.sort_by_key(|node| node.x);
            assert_eq!(needed, wanted, "steps {steps}");
            assert!(tables.bricks.len() >= 2, "the row crosses a brick");
        }
    }
}
