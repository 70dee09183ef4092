//! Stage 3 of an LMM frame, node demand: for every shading point, the nodes
//! of its half-ball (steps 1–2) and the lights that can reach it; merged
//! into one sorted list of distinct (node, light word) entries with the
//! light bits some point needs there.

use glam::IVec3;
use rayon::prelude::*;

use super::LightMesh;
use crate::render::light::RenderLight;
use crate::render::surface::ShadingPoint;

/// Light bits (word `word` of the mask, lights `64·word ..`) that some
/// shading point needs at `node`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeDemand {
    pub node: IVec3,
    pub word: u32,
    pub needed: u64,
}

/// Points per parallel chunk: large enough that neighbours share nodes and
/// the local merge removes most duplicates.
const CHUNK: usize = 4096;

impl LightMesh {
    /// The distinct (node, word) entries `points` need, sorted.
    pub fn demand(&self, points: &[ShadingPoint], lights: &[RenderLight]) -> Vec<NodeDemand> {
        let chunks: Vec<Vec<NodeDemand>> = points
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut entries = Vec::new();
                let mut nodes = Vec::new();
                let mut reach = Vec::new();
                for point in chunk {
                    reaching_lights(point, lights, &mut reach);
                    if reach.iter().all(|&word| word == 0) {
                        continue;
                    }
                    nodes.clear();
                    self.lattice.half_ball(
                        point.position,
                        point.geometric_normal,
                        self.radius(),
                        &mut nodes,
                    );
                    for &node in &nodes {
                        for (word, &needed) in reach.iter().enumerate() {
                            if needed != 0 {
                                entries.push(NodeDemand {
                                    node,
                                    word: word as u32,
                                    needed,
                                });
                            }
                        }
                    }
                }
                merge(entries)
            })
            .collect();
        merge(chunks.into_iter().flatten().collect())
    }
}

/// Bit i set when light i can reach `point` (what shading will ask for).
pub fn reaching_lights(point: &ShadingPoint, lights: &[RenderLight], words: &mut Vec<u64>) {
    words.clear();
    words.resize(lights.len().div_ceil(64).max(1), 0);
    for (index, light) in lights.iter().enumerate() {
        if point.reaching(light).is_some() {
            words[index / 64] |= 1 << (index % 64);
        }
    }
}

/// Sorts by (node, word) and ORs duplicates together.
fn merge(mut entries: Vec<NodeDemand>) -> Vec<NodeDemand> {
    entries.par_sort_unstable_by_key(|entry| (entry.node.to_array(), entry.word));
    let mut merged: Vec<NodeDemand> = Vec::with_capacity(entries.len() / 4);
    for entry in entries {
        match merged.last_mut() {
            Some(last) if last.node == entry.node && last.word == entry.word => {
                last.needed |= entry.needed
            }
            _ => merged.push(entry),
        }
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_dedupes_and_ors_the_needed_bits() {
        let a = IVec3::new(1, 2, 3);
        let b = IVec3::new(-1, 0, 0);
        let entries = vec![
            NodeDemand {
                node: a,
                word: 0,
                needed: 1,
            },
            NodeDemand {
                node: b,
                word: 0,
                needed: 4,
            },
            NodeDemand {
                node: a,
                word: 0,
                needed: 2,
            },
            NodeDemand {
                node: a,
                word: 1,
                needed: 8,
            },
        ];
        let merged = merge(entries);
        assert_eq!(merged.len(), 3);
        let first_a = merged.iter().find(|e| e.node == a && e.word == 0).unwrap();
        assert_eq!(first_a.needed, 3);
    }
}
