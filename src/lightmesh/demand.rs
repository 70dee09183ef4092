//! Stage 3 of an LMM frame, node demand: for every shading point, the lights
//! that can reach it and the nodes of its half-ball (steps 1–2), gathered
//! into per-brick tables of the light bits some point needs at each node.
//! Neighbouring points share most of their nodes; OR-ing into a brick-shaped
//! table merges them without sorting millions of entries.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use wide::f32x8;

use super::faint::LampTerms;
use super::lattice::{Lattice, Row, Spread};
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
    /// The half-ball walked: its lattice, whose node i is the mesh's
    /// i·`steps`, and its radius.
    lattice: Lattice,
    radius: f32,
    steps: i32,
    /// The runs open ([`OPEN_RUNS`]), a ring whose oldest is at `oldest`,
    /// and their first points, to find the few near enough to try.
    runs: Vec<Run>,
    oldest: usize,
    firsts: RunFirsts,
    rows: Vec<Row>,
    gathered: Windows,
    /// The lights the gathered nodes are needed for.
    lights: Vec<u64>,
}

impl Walk {
    fn new((lattice, radius): (Lattice, f32), steps: i32, words: usize) -> Walk {
        Walk {
            lattice,
            radius,
            steps,
            runs: (0..OPEN_RUNS).map(|_| Run::new(words)).collect(),
            oldest: 0,
            firsts: RunFirsts::new(),
            rows: Vec::new(),
            gathered: Windows::new(),
            lights: vec![0; words],
        }
    }

    /// Needs `lights` at the nodes of the half-ball of the point at `p`
    /// with normal `n`: through the newest open run it joins, or one it
    /// starts in place of the oldest, which is asked of the tables.
    fn add(&mut self, tables: &mut BrickTables, (p, n): (Vec3, Vec3), lights: &[u64]) {
        let (lattice, radius) = (&self.lattice, self.radius);
        // Bit j: the run j places after the oldest, so newest first is
        // highest first.
        let mut near =
            (self.firsts.near(p, RUN_STEPS * lattice.h)).rotate_right(self.oldest as u32);
        while near != 0 {
            let after_oldest = RunBits::BITS - 1 - near.leading_zeros();
            near &= !(1 << after_oldest);
            let index = (self.oldest + after_oldest as usize) % OPEN_RUNS;
            if self.runs[index].joins(lattice, radius, (p, n), lights) {
                return;
            }
        }
        let oldest = self.oldest;
        self.ask_run(tables, oldest);
        self.runs[oldest].start((p, n), lights);
        self.firsts.set(oldest, p);
        self.oldest = (oldest + 1) % OPEN_RUNS;
    }

    /// Asks the tables for everything added, every run open: after the
    /// chunk's last point.
    fn finish(&mut self, tables: &mut BrickTables) {
        for index in 0..OPEN_RUNS {
            self.ask_run(tables, index);
        }
        self.flush(tables);
    }

    /// Needs the lights of run `index` at the rows that hold its points'
    /// half-balls.
    fn ask_run(&mut self, tables: &mut BrickTables, index: usize) {
        let Some((p, n, spread)) = self.runs[index].end() else {
            return;
        };
        self.firsts.set(index, Vec3::INFINITY);
        let (lattice, radius) = (self.lattice, self.radius);
        let rows = self.start();
        match spread == Spread::default() {
            true => lattice.half_ball_rows(p, n, radius, |row| rows.push(row)),
            false => lattice.spread_half_ball_rows(p, n, radius, spread, |row| rows.push(row)),
        }
        let lights = std::mem::take(&mut self.runs[index].lights);
        self.need(tables, &lights);
        self.runs[index].lights = lights;
    }

    /// The rows to gather next go here.
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

/// How far a point may lie from a run's first point to join it ([`Run`]),
/// in steps of the walk's lattice.
const RUN_STEPS: f32 = 0.5;
/// How far it may lie from the first point's plane, in the same steps:
/// points of one flat triangle lie on it to rounding.
const RUN_PLANE_STEPS: f32 = 1.0 / 32.0;
/// Runs a walk keeps open: the 16 points of a row of a film tile (the CPU
/// backend shades tiles of 16×16 pixels, row by row), so a point can join
/// the run begun above it in the tile's row before. On the 64-lamp street
/// at 1920×1080 this halves the runs asked (1.22 M for one open run, 0.65 M
/// for sixteen) and the rows walked (20.5 M, 9.7 M); a second row of runs
/// open (32) adds under 1% to that.
const OPEN_RUNS: usize = RunBits::BITS as usize;
/// A bit per open run.
type RunBits = u16;

/// The first points of a walk's open runs, by axis, a run per lane
/// (infinitely far where it is closed): a point's distance to all of them
/// takes a few SIMD operations, and only runs near enough are tried. Where
/// points lie more than half a step apart (the far surfaces of a
/// fly-through), none is, and trying them one by one cost more than the
/// runs saved.
struct RunFirsts {
    /// Per axis, per block of [`LANES`] runs.
    axes: [[f32x8; OPEN_RUNS / LANES]; 3],
}

impl RunFirsts {
    fn new() -> RunFirsts {
        RunFirsts {
            axes: [[f32x8::splat(f32::INFINITY); OPEN_RUNS / LANES]; 3],
        }
    }

    fn set(&mut self, run: usize, first: Vec3) {
        for (axis, blocks) in self.axes.iter_mut().enumerate() {
            blocks[run / LANES].as_mut_array()[run % LANES] = first[axis];
        }
    }

    /// Bit i set where run i's first point lies within `reach` of `p`.
    fn near(&self, p: Vec3, reach: f32) -> RunBits {
        let mut near = 0;
        for block in 0..OPEN_RUNS / LANES {
            let offset = |axis: usize| self.axes[axis][block] - f32x8::splat(p[axis]);
            let (x, y, z) = (offset(0), offset(1), offset(2));
            let within = (x * x + y * y + z * z).simd_le(f32x8::splat(reach * reach));
            near |= (within.to_bitmask() as RunBits) << (LANES * block);
        }
        near
    }
}

/// Points near each other whose half-balls one walk covers. Beside each
/// other on a plane, points' sets hold nearly the same nodes: on the
/// 64-lamp street at 1920×1080, of the points that ask their wide set, two
/// in three lie within a mesh step (half a step of its lattice) of the last
/// point that began a run, with its normal and its lamps, and one in two
/// within half a mesh step. Such a point joins that run instead of walking
/// its own set, and the run asks once for the rows of the ball grown to
/// hold all of its points' sets ([`Lattice::spread_half_ball_rows`]). That needs
/// every node each point's own set would, and a rim beyond: bits filled
/// that no point of the frame reads, which cannot change an image (a frame
/// that reuses masks holds more still). A run of one point asks for its
/// own set alone.
struct Run {
    /// The first point's position and normal; None between runs.
    first: Option<(Vec3, Vec3)>,
    lights: Vec<u64>,
    spread: Spread,
}

impl Run {
    fn new(words: usize) -> Run {
        Run {
            first: None,
            lights: vec![0; words],
            spread: Spread::default(),
        }
    }

    /// Whether the point at `p` with normal `n`, needing `lights` of the
    /// half-ball of `radius` on `lattice`, joined the run: it has the
    /// run's normal and lights, and lies near enough to its first point
    /// for the grown ball to hold.
    fn joins(
        &mut self,
        lattice: &Lattice,
        radius: f32,
        (p, n): (Vec3, Vec3),
        lights: &[u64],
    ) -> bool {
        let Some((first, normal)) = self.first else {
            return false;
        };
        if normal != n || self.lights != lights {
            return false;
        }
        let spread = self.spread.holding(first, n, p);
        let joins = spread.distance <= RUN_STEPS * lattice.h
            && spread.offset <= RUN_PLANE_STEPS * lattice.h
            && spread.fits(lattice, first, radius);
        if joins {
            self.spread = spread;
        }
        joins
    }

    /// A new run from the point at `p` with normal `n`.
    fn start(&mut self, (p, n): (Vec3, Vec3), lights: &[u64]) {
        self.first = Some((p, n));
        self.lights.copy_from_slice(lights);
        self.spread = Spread::default();
    }

    /// The run's first point and spread, ending it.
    fn end(&mut self) -> Option<(Vec3, Vec3, Spread)> {
        self.first.take().map(|(p, n)| (p, n, self.spread))
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
                    let mut half_ball = Walk::new((self.lattice, self.radius()), 1, words);
                    let mut wide_set = wide.map(|ball| {
                        Walk::new((ball.lattice, ball.radius), wide_ball::STEPS, words)
                    });
                    let mut lamps_reached = vec![0; words];
                    let per_point = chunk_reach.chunks(words).zip(chunk_faint.chunks(words));
                    for (point, (point_reach, point_faint)) in chunk.iter().zip(per_point) {
                        if point_reach.iter().all(|&word| word == 0) {
                            continue;
                        }
                        let (p, n) = (point.position, point.geometric_normal);
                        half_ball.add(&mut tables, (p, n), point_reach);
                        let Some(wide_set) = &mut wide_set else {
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
                        wide_set.add(&mut tables, (p, n), &lamps_reached);
                    }
                    half_ball.finish(&mut tables);
                    if let Some(wide_set) = &mut wide_set {
                        wide_set.finish(&mut tables);
                    }
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
            let mut walk = Walk::new((Lattice::new(0.1), 0.25), steps, words);
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

    /// Each point's half-ball, for its lights, and its wide set, for its
    /// lamps, are needed where points form runs (a row of them a fraction
    /// of a step apart on a floor) and where they do not (far apart, a
    /// wall's normal between the floor's): the runs' grown balls hold every
    /// node, and add only a rim.
    #[test]
    fn runs_need_every_node_of_their_points_sets() {
        use crate::lightmesh::masks::join;
        use crate::lightmesh::penumbra::Penumbra;
        use crate::render::light::{LightSource, RenderLight};
        use std::collections::HashSet;

        let lamp = |x: f32, z: f32| RenderLight {
            source: LightSource::Point {
                position: Vec3::new(x, 3.0, z),
            },
            power: Vec3::splat(50.0),
            range: None,
            lamp_radius: 0.2,
        };
        let lights = [lamp(-2.0, 0.5), lamp(1.0, -1.0), lamp(4.0, 2.0)];
        let mut mesh = LightMesh::new(Lattice::new(0.1), 2.5, lights.len(), 1 << 30);
        mesh.penumbra = Penumbra::Wide;
        let point = ShadingPoint::matte;
        let mut points = Vec::new();
        for i in 0..120 {
            let x = -1.5 + 0.031 * i as f32;
            points.push(point(Vec3::new(x, 0.0, 0.013 * (i % 4) as f32), Vec3::Y));
            if i % 10 == 0 {
                points.push(point(Vec3::new(2.0, 0.5 + 0.02 * i as f32, x), Vec3::X));
                points.push(point(Vec3::new(3.0 * x, 0.0, 5.0), Vec3::Y));
            }
        }
        // A patch of the floor in raster order, as a tile of the film
        // shades it, where a row's points can join the runs of the row
        // before. After every fourth floor point comes one on a wall of
        // its own: more walls than runs stay open, so the oldest runs are
        // asked while the floor's are open.
        for row in 0..12 {
            for column in 0..16 {
                let at = Vec3::new(0.7 + 0.023 * column as f32, 0.0, -2.0 + 0.019 * row as f32);
                points.push(point(at, Vec3::Y));
                if column % 4 == 0 {
                    let normal = Vec3::new(1.0, 0.0, 0.1 * (row * 4 + column / 4) as f32);
                    points.push(point(at + Vec3::Y, normal.normalize()));
                }
            }
        }
        let demand = mesh.demand(&points, &LightLanes::new(&lights)).unwrap();
        let needed = |node: IVec3| {
            let (brick, slot) = split(node);
            (demand
                .bricks
                .binary_search_by_key(&brick.to_array(), |b| b.brick.to_array()))
            .map_or(0, |at| demand.bricks[at].needed[slot])
        };
        let ball = WideBall::of(&mesh);
        let lamps = wide_ball::lamps(&lights, 1);
        let (mut wide_sets, mut half_balls) = (HashSet::new(), HashSet::new());
        for (index, point) in points.iter().enumerate() {
            let (reach, faint) = demand.of_point(index);
            let asked = reach[0] & lamps[0] & !faint[0];
            assert_ne!(asked, 0, "point {index} asks no lamp");
            let (p, n) = (point.position, point.geometric_normal);
            let mut nodes = Vec::new();
            ball.nodes(p, n, &mut nodes);
            for node in nodes {
                assert_eq!(needed(node) & asked, asked, "{node} of point {index}");
                wide_sets.insert(node);
            }
            let mut own = Vec::new();
            mesh.lattice.half_ball(p, n, mesh.radius(), &mut own);
            for node in own {
                assert_eq!(needed(node) & reach[0], reach[0], "{node} of point {index}");
                half_balls.insert(node);
            }
        }
        let rim = (demand.bricks.iter())
            .flat_map(|brick| (0..BRICK_NODES).map(move |slot| join(brick.brick, slot)))
            .filter(|node| needed(*node) != 0 && !wide_sets.contains(node))
            .filter(|node| !half_balls.contains(node))
            .count();
        assert!(
            rim > 0 && rim < wide_sets.len() / 4,
            "{rim} nodes needed beyond the {} of the points' wide sets",
            wide_sets.len()
        );
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
