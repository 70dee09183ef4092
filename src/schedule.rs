//! Which frames to render and when they happen. [`FrameSet`] turns the
//! CLI's RANGE argument into a sorted list of frame numbers; [`Timeline`]
//! maps a frame to its time in seconds, which the pose of the scene is
//! sampled at; [`FrameDelta`] says what changed from one rendered frame to
//! the next, which decides what a frame must recompute, and brings the
//! world up to the new frame ([`FrameDelta::update_world`]).

use std::fmt;
use std::str::FromStr;

use crate::accel::World;
use crate::lightmesh::invalidate::ChangedRegion;
use crate::render::frame::FrameScene;
use crate::render::light::{LightSource, RenderLight};

/// The most frames one set may hold: beyond it a typo (`1-1000000000`) is
/// far likelier than a real shot, and the list would take gigabytes.
pub const MAX_FRAMES: u64 = 10_000_000;

/// A sorted set of distinct frame numbers, never empty.
///
/// Written as comma-separated items, each a single frame `N`, a Rust-style
/// half-open range `A..B`, an inclusive range `A..=B`, or a farm-style
/// inclusive range `A-B`: `0..24`, `1-30,47`, `10,2..=4`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameSet {
    frames: Vec<u32>,
}

/// Why a RANGE argument is not a frame set; each message quotes it.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub enum FrameSetError {
    #[error("frame range `{input}` has an empty item; write e.g. `1-30,47`")]
    EmptyItem { input: String },
    #[error("frame range `{item}` in `{input}` holds no frames{hint}")]
    EmptyRange {
        input: String,
        item: String,
        hint: &'static str,
    },
    #[error("frame range `{input}`: `{text}` is not a frame number (0 to {max})", max = u32::MAX)]
    Number { input: String, text: String },
    #[error("frame range `{input}` holds {count} frames; at most {MAX_FRAMES} are allowed")]
    TooMany { input: String, count: u64 },
}

impl FrameSet {
    /// Parses the RANGE syntax described on [`FrameSet`].
    pub fn parse(input: &str) -> Result<FrameSet, FrameSetError> {
        let mut intervals = input
            .split(',')
            .map(|item| parse_item(input, item.trim()))
            .collect::<Result<Vec<_>, _>>()?;
        intervals.sort_unstable();
        // Merge overlapping and touching intervals, so the count is exact
        // before anything large is allocated.
        let mut merged: Vec<(u32, u32)> = Vec::with_capacity(intervals.len());
        for (start, end) in intervals {
            match merged.last_mut() {
                Some(last) if u64::from(start) <= u64::from(last.1) + 1 => {
                    last.1 = last.1.max(end);
                }
                _ => merged.push((start, end)),
            }
        }
        let count: u64 = merged
            .iter()
            .map(|&(start, end)| u64::from(end - start) + 1)
            .sum();
        if count > MAX_FRAMES {
            return Err(FrameSetError::TooMany {
                input: input.to_owned(),
                count,
            });
        }
        let frames = merged
            .into_iter()
            .flat_map(|(start, end)| start..=end)
            .collect();
        Ok(FrameSet { frames })
    }

    /// The frames, ascending, without repeats.
    pub fn frames(&self) -> &[u32] {
        &self.frames
    }

    /// How many frames the set holds (at least one).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Always false: parsing rejects sets without frames. Present because a
    /// `len` without it surprises readers (and clippy).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
}

impl FromStr for FrameSet {
    type Err = FrameSetError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        FrameSet::parse(input)
    }
}

/// The shortest farm-style form: runs as `A-B`, lone frames as `N`.
impl fmt::Display for FrameSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut rest = self.frames.as_slice();
        let mut separator = "";
        while let Some(&start) = rest.first() {
            let run = rest
                .iter()
                .zip(start..)
                .take_while(|(&frame, expected)| frame == *expected)
                .count();
            let end = rest[run - 1];
            if run == 1 {
                write!(f, "{separator}{start}")?;
            } else {
                write!(f, "{separator}{start}-{end}")?;
            }
            separator = ",";
            rest = &rest[run..];
        }
        Ok(())
    }
}

/// One comma-separated item as an inclusive interval.
fn parse_item(input: &str, item: &str) -> Result<(u32, u32), FrameSetError> {
    if item.is_empty() {
        return Err(FrameSetError::EmptyItem {
            input: input.to_owned(),
        });
    }
    let number = |text: &str| {
        let text = text.trim();
        // `u32::from_str` takes a leading `+`; a frame number should not.
        if text.starts_with('+') {
            return Err(FrameSetError::Number {
                input: input.to_owned(),
                text: text.to_owned(),
            });
        }
        text.parse::<u32>().map_err(|_| FrameSetError::Number {
            input: input.to_owned(),
            text: text.to_owned(),
        })
    };
    let empty = |hint| FrameSetError::EmptyRange {
        input: input.to_owned(),
        item: item.to_owned(),
        hint,
    };
    if let Some((a, b)) = item.split_once("..=") {
        let (start, end) = (number(a)?, number(b)?);
        return if start <= end {
            Ok((start, end))
        } else {
            Err(empty(""))
        };
    }
    if let Some((a, b)) = item.split_once("..") {
        let (start, end) = (number(a)?, number(b)?);
        return if start < end {
            Ok((start, end - 1))
        } else if start == end {
            Err(empty("; A..B excludes B, write A..=B to include it"))
        } else {
            Err(empty(""))
        };
    }
    if let Some((a, b)) = item.split_once('-') {
        let (start, end) = (number(a)?, number(b)?);
        return if start <= end {
            Ok((start, end))
        } else {
            Err(empty(""))
        };
    }
    let frame = number(item)?;
    Ok((frame, frame))
}

/// Maps frame numbers to scene time. Frame `f` is sampled at `f / fps`
/// seconds, so frame 0 shows the animation's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timeline {
    pub fps: f64,
}

impl Timeline {
    /// The time in seconds at which `frame` samples the animation.
    pub fn time_of(&self, frame: u32) -> f64 {
        f64::from(frame) / self.fps
    }
}

/// What changed between two consecutive rendered frames. It decides the
/// work of the next one: moved objects update the world's top level,
/// deformed ones refit their own structure, moved objects and lights
/// invalidate light-mesh bits, and a frame where nothing changed is copied.
/// Light colour, intensity, range and cones, the camera's projection and
/// material factors change the image but no visibility, so they invalidate
/// nothing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameDelta {
    /// The camera's placement or projection (field of view, far plane)
    /// changed.
    pub camera_moved: bool,
    /// Lights (indices into `FrameScene::lights`) whose position or
    /// direction changed: their mask bits are stale.
    pub lights_moved: Vec<usize>,
    /// Some light changed colour, intensity, range or cone: the image
    /// changes, no mask bit does. (Range and cones decide which lights a
    /// point asks the light mesh for, not what a node's bit says; a bit
    /// first asked for after a change is computed then.)
    pub lights_changed: bool,
    /// Some material factor changed: the image changes, nothing else.
    pub materials_changed: bool,
    /// Objects (indices into `FrameScene::objects`) moved rigidly.
    pub objects_moved: Vec<usize>,
    /// Objects whose mesh deformed (skins, morph targets).
    pub objects_deformed: Vec<usize>,
}

impl FrameDelta {
    /// The first frame of a run: everything is new.
    pub fn first(frame: &FrameScene) -> FrameDelta {
        let dynamic = |(index, object): (usize, &crate::render::frame::PlacedObject)| {
            object.dynamic.then_some(index)
        };
        FrameDelta {
            camera_moved: true,
            lights_moved: (0..frame.lights.len()).collect(),
            lights_changed: true,
            materials_changed: true,
            objects_moved: frame
                .objects
                .iter()
                .enumerate()
                .filter_map(dynamic)
                .collect(),
            objects_deformed: (0..frame.objects.len())
                .filter(|&i| frame.deformed[i].is_some())
                .collect(),
        }
    }

    /// What changed from `before` to `after` (two placements of the same
    /// scene with the same anchor).
    pub fn between(before: &FrameScene, after: &FrameScene) -> FrameDelta {
        let moved_light = |(index, (a, b)): (usize, (&RenderLight, &RenderLight))| {
            let moved = match (a.source, b.source) {
                (
                    LightSource::Directional { towards: x },
                    LightSource::Directional { towards: y },
                ) => x != y,
                _ => a.position() != b.position(),
            };
            moved.then_some(index)
        };
        let pairs = || before.lights.iter().zip(&after.lights).enumerate();
        FrameDelta {
            camera_moved: before.camera != after.camera,
            lights_moved: pairs().filter_map(moved_light).collect(),
            lights_changed: pairs().any(|(_, (a, b))| a != b),
            materials_changed: before.materials != after.materials,
            objects_moved: (0..after.objects.len())
                .filter(|&i| before.objects[i].to_render != after.objects[i].to_render)
                .collect(),
            objects_deformed: (0..after.objects.len())
                .filter(|&i| before.deformed[i] != after.deformed[i])
                .collect(),
        }
    }

    /// Brings `world` from the frame before to `after`, the frame this
    /// delta leads to: moved objects get new instance transforms, deformed
    /// ones new positions. Returns the regions where geometry changed, for
    /// the light mesh to invalidate (see [`World::update_object`]).
    pub fn update_world(&self, world: &mut World, after: &FrameScene) -> Vec<ChangedRegion> {
        let mut changed: Vec<usize> = (self.objects_moved.iter())
            .chain(&self.objects_deformed)
            .copied()
            .collect();
        changed.sort_unstable();
        changed.dedup();
        changed
            .into_iter()
            .flat_map(|object| {
                let deformed = after.deformed[object]
                    .as_deref()
                    .filter(|_| self.objects_deformed.contains(&object));
                world.update_object(
                    object,
                    after.objects[object].to_render,
                    deformed.map(|mesh| &mesh.positions[..]),
                    self.objects_moved.contains(&object),
                )
            })
            .map(ChangedRegion::from)
            .collect()
    }

    /// Nothing that the image depends on changed: the frame is a copy.
    pub fn is_still(&self) -> bool {
        !self.camera_moved
            && !self.lights_changed
            && !self.materials_changed
            && self.objects_moved.is_empty()
            && self.objects_deformed.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn frames(input: &str) -> Vec<u32> {
        FrameSet::parse(input).unwrap().frames().to_vec()
    }

    #[test]
    fn parses_each_form() {
        assert_eq!(frames("0..4"), [0, 1, 2, 3]);
        assert_eq!(frames("2..=4"), [2, 3, 4]);
        assert_eq!(frames("7"), [7]);
        assert_eq!(frames("1-3,47"), [1, 2, 3, 47]);
        assert_eq!(frames(" 10 , 2..=3 ,1-2 "), [1, 2, 3, 10]);
        assert_eq!(frames("5..=5"), [5]);
        assert_eq!(frames("4294967295"), [u32::MAX]);
        assert_eq!(frames("4294967294..=4294967295"), [u32::MAX - 1, u32::MAX]);
    }

    #[test]
    fn sorts_and_removes_repeats() {
        assert_eq!(frames("9,3,3,1-4,2..6"), [1, 2, 3, 4, 5, 9]);
    }

    #[test]
    fn empty_ranges_are_errors() {
        let error = FrameSet::parse("5..5").unwrap_err();
        assert!(error.to_string().contains("A..=B"), "{error}");
        for input in ["5..2", "5..=4", "9-3", "", "1,,2", "3,"] {
            assert!(FrameSet::parse(input).is_err(), "{input}");
        }
    }

    #[test]
    fn garbage_is_an_error_quoting_the_input() {
        for input in [
            "a",
            "1..x",
            "-3",
            "1.5",
            "1..2..3",
            "+4",
            "1 2",
            "4294967296",
        ] {
            let message = FrameSet::parse(input).unwrap_err().to_string();
            assert!(message.contains(input), "{input}: {message}");
        }
    }

    #[test]
    fn huge_sets_are_refused_before_allocating() {
        let error = FrameSet::parse("0..=4294967295").unwrap_err();
        assert_eq!(
            error,
            FrameSetError::TooMany {
                input: "0..=4294967295".into(),
                count: 1 << 32
            }
        );
        // Overlaps are counted once: this is exactly the limit.
        let at_limit = FrameSet::parse("0..10000000,0-9999999").unwrap();
        assert_eq!(at_limit.len() as u64, MAX_FRAMES);
        assert!(FrameSet::parse("0..=10000000").is_err());
    }

    #[test]
    fn displays_the_shortest_form() {
        let set = FrameSet::parse("47,1..31,2,50..=51").unwrap();
        assert_eq!(set.to_string(), "1-30,47,50-51");
    }

    #[test]
    fn timeline_divides_by_fps() {
        let timeline = Timeline { fps: 24.0 };
        assert_eq!(timeline.time_of(0), 0.0);
        assert_eq!(timeline.time_of(48), 2.0);
        assert_eq!(
            Timeline { fps: 30.0 }.time_of(u32::MAX),
            u32::MAX as f64 / 30.0
        );
    }

    proptest! {
        #[test]
        fn ranges_match_rust_ranges(start in 0u32..5000, len in 1u32..500) {
            let end = start + len;
            let half_open: Vec<u32> = (start..end).collect();
            let inclusive: Vec<u32> = (start..=end).collect();
            prop_assert_eq!(frames(&format!("{start}..{end}")), half_open);
            prop_assert_eq!(frames(&format!("{start}..={end}")), inclusive.clone());
            prop_assert_eq!(frames(&format!("{start}-{end}")), inclusive);
        }

        #[test]
        fn lists_parse_to_sorted_distinct_frames_and_display_round_trips(
            list in proptest::collection::vec(
                prop_oneof![0u32..100, any::<u32>()], 1..40)
        ) {
            let text = list.iter().map(u32::to_string).collect::<Vec<_>>().join(",");
            let set = FrameSet::parse(&text).unwrap();
            let mut expected = list.clone();
            expected.sort_unstable();
            expected.dedup();
            prop_assert_eq!(set.frames(), expected.as_slice());
            prop_assert_eq!(FrameSet::parse(&set.to_string()).unwrap(), set);
        }

        #[test]
        fn time_increases_with_frame(frame in 0u32..u32::MAX, fps in 0.1f64..1000.0) {
            let timeline = Timeline { fps };
            prop_assert!(timeline.time_of(frame + 1) > timeline.time_of(frame));
        }
    }
}
