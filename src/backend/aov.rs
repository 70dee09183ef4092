//! A frame's AOV layers (`--aovs`), made band by band beside the beauty
//! from the same shading points: the `light` layers from each point's
//! light terms as the shade stage logged them (`render/light_terms.rs`),
//! weighted by the point's path throughput and resolved like the beauty,
//! so that they sum to it within rounding; `albedo`, `normal` and `depth`
//! from the camera's own hits. The beauty's stages run unchanged: only
//! the shade stage keeps its terms where the `light` AOV asks for them.

use glam::{UVec2, Vec3};

use super::sampling::film_position;
use crate::output::AovLayer;
use crate::render::light_terms::PointTerms;
use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;
use crate::scene::SceneDesc;
use crate::settings::Aov;

/// The layers of the `light` AOV, and which layer each of a frame's
/// lights adds to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightLayers {
    /// Layer names, safe in EXR channel names and unique.
    pub names: Vec<String>,
    /// Per light of the frame, in the frame's order, its layer.
    pub layer_of: Vec<usize>,
}

impl LightLayers {
    /// The layers of `scene`'s lights, in the frame's light order (the
    /// nodes that carry a light, in node order): one per group
    /// (`extras.group`) and one per light without a group, named after
    /// the group, else the light, else its node, else `light<i>`; every
    /// character but letters, digits, `_` and `-` becomes `_` (a dot
    /// would start a new layer in readers), and a name taken already gets
    /// `_2`, `_3`, ….
    pub fn of(scene: &SceneDesc) -> LightLayers {
        let mut layers = LightLayers {
            names: Vec::new(),
            layer_of: Vec::new(),
        };
        let mut groups: Vec<(&str, usize)> = Vec::new();
        let lit_nodes =
            (scene.nodes.iter()).filter_map(|node| Some((node, scene.lights.get(node.light?)?)));
        for (index, (node, light)) in lit_nodes.enumerate() {
            let grouped = (light.group.as_deref())
                .map(|group| (group, groups.iter().find(|(name, _)| *name == group)));
            let layer = match grouped {
                Some((_, Some(&(_, layer)))) => layer,
                Some((group, None)) => {
                    let layer = layers.add(group, index);
                    groups.push((group, layer));
                    layer
                }
                None => {
                    let name = (light.name.as_deref()).or(node.name.as_deref());
                    layers.add(name.unwrap_or_default(), index)
                }
            };
            layers.layer_of.push(layer);
        }
        layers
    }

    /// A new layer named after `name` (of light `index` of the frame).
    fn add(&mut self, name: &str, index: usize) -> usize {
        let safe: String = name
            .chars()
            .map(|c| match c {
                'a'..='z' | 'A'..='Z' | '0'..='9' | '_' | '-' => c,
                _ => '_',
            })
            .collect();
        let base = if safe.is_empty() {
            format!("light{index}")
        } else {
            safe
        };
        let mut unique = base.clone();
        for suffix in 2.. {
            if !self.names.contains(&unique) {
                break;
            }
            unique = format!("{base}_{suffix}");
        }
        self.names.push(unique);
        self.names.len() - 1
    }
}

/// A frame's AOV layers as its bands add to them.
pub struct AovFrame {
    aovs: Vec<Aov>,
    lights: LightLayers,
    /// Per AOV in `aovs` order its layers (the `light` AOV: one per light
    /// layer, then `other`), filled row after row.
    layers: Vec<AovLayer>,
}

impl AovFrame {
    /// The layers `job` asks for, empty; None when it asks for none.
    pub fn new(job: &FrameJob) -> Option<AovFrame> {
        if job.aovs.is_empty() {
            return None;
        }
        let lights = LightLayers::of(job.scene);
        let rgb = |prefix: &str, axes: [&str; 3]| AovLayer {
            channels: axes.map(|axis| format!("{prefix}.{axis}")).to_vec(),
            values: Vec::new(),
        };
        let layers = (job.aovs.iter())
            .flat_map(|aov| match aov {
                Aov::Light => (lights.names.iter())
                    .map(|name| format!("light.{name}"))
                    .chain(["other".to_owned()])
                    .map(|prefix| rgb(&prefix, ["R", "G", "B"]))
                    .collect(),
                Aov::Albedo => vec![rgb("albedo", ["R", "G", "B"])],
                Aov::Normal => vec![rgb("N", ["X", "Y", "Z"])],
                Aov::Depth => vec![AovLayer {
                    channels: vec!["Z".into()],
                    values: Vec::new(),
                }],
            })
            .collect();
        Some(AovFrame {
            aovs: job.aovs.to_vec(),
            lights,
            layers,
        })
    }

    /// Whether the shade stage must log each point's light terms.
    pub fn wants_light_terms(job: &FrameJob) -> bool {
        job.aovs.contains(&Aov::Light)
    }

    /// Adds the pixels of the band `rows`: its shading `points` (the first
    /// `primary` of them camera hits) with the shade stage's `terms`, one
    /// per `chunk` points.
    pub fn add_band<T: PointTerms>(
        &mut self,
        job: &FrameJob,
        rows: std::ops::Range<u32>,
        points: &[ShadingPoint],
        primary: usize,
        terms: &[T],
        chunk: usize,
    ) {
        let camera_hits = &points[..primary];
        let samples = ((rows.end - rows.start) * job.width * job.spp) as usize;
        let mut covered = vec![false; samples];
        for point in camera_hits {
            covered[point.sample as usize] = true;
        }
        let band = Band {
            job,
            rows,
            camera_hits,
            covered,
        };
        let mut layers = self.layers.iter_mut();
        for aov in &self.aovs {
            let count = match aov {
                Aov::Light => self.lights.names.len() + 1,
                _ => 1,
            };
            let mine: Vec<&mut AovLayer> = layers.by_ref().take(count).collect();
            match aov {
                Aov::Light => {
                    let lights = (&self.lights.layer_of[..], count);
                    let sent = band.light_samples(points, terms, chunk, lights);
                    for (layer, out) in mine.into_iter().enumerate() {
                        let other = layer == count - 1;
                        band.resolve_mean(out, |sample, covered| {
                            let value = sent[sample * count + layer];
                            if other {
                                job.environment.sample_radiance(value, covered)
                            } else {
                                value
                            }
                        });
                    }
                }
                Aov::Albedo => {
                    let albedo = band.camera_samples(|point| point.material.base_color);
                    for out in mine {
                        band.resolve_mean(out, |s, _| albedo[s]);
                    }
                }
                Aov::Normal => {
                    let normal = band.camera_samples(|point| point.shading_normal);
                    for out in mine {
                        band.resolve_mean(out, |s, _| normal[s]);
                    }
                }
                Aov::Depth => mine.into_iter().for_each(|out| band.resolve_depth(out)),
            }
        }
    }

    /// The finished layers.
    pub fn into_layers(self) -> Vec<AovLayer> {
        self.layers
    }
}

/// One band's view of the frame.
struct Band<'a> {
    job: &'a FrameJob<'a>,
    rows: std::ops::Range<u32>,
    camera_hits: &'a [ShadingPoint],
    /// Whether each sample's camera ray hit something.
    covered: Vec<bool>,
}

impl Band<'_> {
    fn samples(&self) -> usize {
        self.covered.len()
    }

    /// Per sample, `value` of its camera hit (zero where it has none).
    fn camera_samples(&self, value: impl Fn(&ShadingPoint) -> Vec3) -> Vec<Vec3> {
        let mut values = vec![Vec3::ZERO; self.samples()];
        for point in self.camera_hits {
            values[point.sample as usize] = value(point);
        }
        values
    }

    /// Per sample and light layer (`layers` of them, `other` last), what
    /// its points sent: each logged term times its point's path
    /// throughput, and what no light brought in `other`.
    fn light_samples<T: PointTerms>(
        &self,
        points: &[ShadingPoint],
        terms: &[T],
        chunk: usize,
        (layer_of, count): (&[usize], usize),
    ) -> Vec<Vec3> {
        let mut sent = vec![Vec3::ZERO; self.samples() * count];
        for (chunk_points, log) in points.chunks(chunk).zip(terms) {
            for (index, point) in chunk_points.iter().enumerate() {
                let at = point.sample as usize * count;
                let terms = log.log().map_or(&[][..], |log| log.point_terms(index));
                for &(light, value) in terms {
                    sent[at + layer_of[light as usize]] += point.weight * value;
                }
                sent[at + count - 1] += point.weight * self.job.environment.unlit(point);
            }
        }
        sent
    }

    /// Appends each pixel's mean of `value(sample, covered)` over its
    /// samples to `out`.
    fn resolve_mean(&self, out: &mut AovLayer, value: impl Fn(usize, bool) -> Vec3) {
        let spp = self.job.spp as usize;
        for pixel in 0..self.samples() / spp {
            let samples = pixel * spp..(pixel + 1) * spp;
            let sum: Vec3 = samples.map(|s| value(s, self.covered[s])).sum();
            out.values.extend((sum / spp as f32).to_array());
        }
    }

    /// Appends each pixel's nearest camera hit, in metres along its ray
    /// (infinite where no sample hit anything), to `out`.
    fn resolve_depth(&self, out: &mut AovLayer) {
        let job = self.job;
        let mut depth = vec![f32::INFINITY; self.samples() / job.spp as usize];
        for point in self.camera_hits {
            let pixel = point.sample / job.spp;
            let (x, y) = (pixel % job.width, self.rows.start + pixel / job.width);
            let film = film_position(UVec2::new(x, y), job.width, point.sample % job.spp, job.spp);
            let ray = job.frame.camera.primary_ray(film, job.width, job.height);
            let distance = (point.position - ray.origin).length();
            let nearest = &mut depth[pixel as usize];
            *nearest = nearest.min(distance);
        }
        out.values.extend(depth);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Light, LightKind, Node};

    fn scene_with(lights: &[(Option<&str>, Option<&str>, Option<&str>)]) -> SceneDesc {
        let mut scene = SceneDesc::default();
        for (index, &(node_name, light_name, group)) in lights.iter().enumerate() {
            scene.lights.push(Light {
                name: light_name.map(str::to_owned),
                kind: LightKind::Point,
                color: Vec3::ONE,
                intensity: 1.0,
                range: None,
                radius: None,
                group: group.map(str::to_owned),
            });
            scene.nodes.push(Node {
                name: node_name.map(str::to_owned),
                light: Some(index),
                ..Node::default()
            });
        }
        scene
    }

    #[test]
    fn names_are_safe_unique_and_fall_back_in_order() {
        let scene = scene_with(&[
            (None, Some("Lamp.Warm"), None),
            (None, Some("Lamp_Warm"), None),
            (Some("pole 3"), None, None),
            (None, None, None),
            (None, Some("Lamp_Warm"), None),
        ]);
        let layers = LightLayers::of(&scene);
        assert_eq!(
            layers.names,
            [
                "Lamp_Warm",
                "Lamp_Warm_2",
                "pole_3",
                "light3",
                "Lamp_Warm_3"
            ]
        );
        assert_eq!(layers.layer_of, [0, 1, 2, 3, 4]);
    }

    #[test]
    fn lights_of_a_group_share_its_layer() {
        let scene = scene_with(&[
            (None, Some("a"), Some("street")),
            (None, Some("b"), None),
            (None, Some("c"), Some("street")),
            (None, Some("d"), Some("cars")),
        ]);
        let layers = LightLayers::of(&scene);
        assert_eq!(layers.names, ["street", "b", "cars"]);
        assert_eq!(layers.layer_of, [0, 1, 0, 2]);
    }
}
