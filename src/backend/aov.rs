//! A frame's AOV layers (`--aovs`), made band by band beside the beauty
//! from the same shading points. Both backends fill one [`BandSamples`]
//! per band — each sample's camera hit (`albedo`, `normal`, `depth`) and,
//! for the `light` AOV, what its points sent per light layer — and
//! [`AovFrame::add_band`] resolves it into pixels, so the two backends'
//! layers can differ only where their samples do. A point's light terms
//! (as the shade stage logged them, `render/light_terms.rs`) are summed
//! per layer in light order, then weighted by the point's path
//! throughput, as the GPU's formula (1) and (2) passes sum them where the
//! point lies (`gpu/shaders/light_layers.wgsl`); so the layers sum to
//! the beauty within rounding. The beauty's stages run unchanged: only
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

    /// The light layers the bands' samples must be split into, where the
    /// `light` AOV is asked for.
    pub fn light_layers(&self) -> Option<&LightLayers> {
        self.aovs.contains(&Aov::Light).then_some(&self.lights)
    }

    /// Adds the pixels of the band whose samples `band` holds.
    pub fn add_band(&mut self, job: &FrameJob, band: &BandSamples) {
        let mut layers = self.layers.iter_mut();
        for aov in &self.aovs {
            let count = match aov {
                Aov::Light => self.lights.names.len() + 1,
                _ => 1,
            };
            let mine = layers.by_ref().take(count);
            match aov {
                Aov::Light => {
                    for (layer, out) in mine.enumerate() {
                        let other = layer == count - 1;
                        band.resolve_mean(job, out, |sample, hit| {
                            let value = band.light[sample * count + layer];
                            if other {
                                job.environment.sample_radiance(value, hit.covered)
                            } else {
                                value
                            }
                        });
                    }
                }
                Aov::Albedo => {
                    mine.for_each(|out| band.resolve_mean(job, out, |_, hit| hit.albedo))
                }
                Aov::Normal => {
                    mine.for_each(|out| band.resolve_mean(job, out, |_, hit| hit.normal))
                }
                Aov::Depth => mine.for_each(|out| band.resolve_depth(job, out)),
            }
        }
    }

    /// The finished layers.
    pub fn into_layers(self) -> Vec<AovLayer> {
        self.layers
    }
}

/// What a camera ray met, for `albedo`, `normal` and `depth`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHit {
    /// Whether it hit anything (the rest is [`FirstHit::MISS`]'s if not).
    pub covered: bool,
    /// The base colour where it hit.
    pub albedo: Vec3,
    /// The world shading normal there.
    pub normal: Vec3,
    /// Metres from the ray's origin.
    pub depth: f32,
}

impl FirstHit {
    /// A camera ray that met nothing: black, no normal, infinitely far.
    pub const MISS: FirstHit = FirstHit {
        covered: false,
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        depth: f32::INFINITY,
    };
}

/// One band's samples as the AOV layers need them: what both backends
/// fill and [`AovFrame::add_band`] resolves.
pub struct BandSamples {
    /// Per sample, its camera hit.
    pub first_hits: Vec<FirstHit>,
    /// Per sample and light layer (`other` last), what its points sent:
    /// each point's terms summed per layer in light order, times its path
    /// throughput, and in `other` what no light brought; empty without
    /// the `light` AOV.
    pub light: Vec<Vec3>,
}

impl BandSamples {
    /// The samples of the band `rows` from its shading `points` (the
    /// first `primary` of them camera hits) with the shade stage's
    /// `terms`, one per `chunk` points, split into `lights` where the
    /// `light` AOV asks for them.
    pub fn from_points<T: PointTerms>(
        job: &FrameJob,
        rows: std::ops::Range<u32>,
        points: &[ShadingPoint],
        primary: usize,
        (terms, chunk): (&[T], usize),
        lights: Option<&LightLayers>,
    ) -> BandSamples {
        let samples = ((rows.end - rows.start) * job.width * job.spp) as usize;
        let mut first_hits = vec![FirstHit::MISS; samples];
        let rays = job.frame.camera.film(job.width, job.height);
        for point in &points[..primary] {
            let pixel = point.sample / job.spp;
            let (x, y) = (pixel % job.width, rows.start + pixel / job.width);
            let film = film_position(UVec2::new(x, y), job.width, point.sample % job.spp, job.spp);
            let ray = rays.through(film);
            first_hits[point.sample as usize] = FirstHit {
                covered: true,
                albedo: point.material.base_color,
                normal: point.shading_normal,
                depth: (point.position - ray.origin).length(),
            };
        }
        let light = lights.map_or_else(Vec::new, |lights| {
            light_samples(job, samples, points, (terms, chunk), lights)
        });
        BandSamples { first_hits, light }
    }

    /// Appends each pixel's mean of `value(sample, its camera hit)` over
    /// its samples, summed in sample order, to `out`.
    fn resolve_mean(
        &self,
        job: &FrameJob,
        out: &mut AovLayer,
        value: impl Fn(usize, &FirstHit) -> Vec3,
    ) {
        let spp = job.spp as usize;
        for pixel in 0..self.first_hits.len() / spp {
            let samples = pixel * spp..(pixel + 1) * spp;
            let sum: Vec3 = samples.map(|s| value(s, &self.first_hits[s])).sum();
            out.values.extend((sum / spp as f32).to_array());
        }
    }

    /// Appends each pixel's nearest camera hit (infinite where no sample
    /// hit anything) to `out`.
    fn resolve_depth(&self, job: &FrameJob, out: &mut AovLayer) {
        let pixels = self.first_hits.chunks(job.spp as usize);
        out.values.extend(pixels.map(|samples| {
            (samples.iter()).fold(f32::INFINITY, |nearest, hit| nearest.min(hit.depth))
        }));
    }
}

/// Per sample and light layer (`lights`' layers, then `other`), what
/// `points` sent: each point's logged `terms` (one log per `chunk`
/// points) summed per layer in light order, each sum times the point's
/// path throughput; in `other`, what no light brought.
fn light_samples<T: PointTerms>(
    job: &FrameJob,
    samples: usize,
    points: &[ShadingPoint],
    (terms, chunk): (&[T], usize),
    lights: &LightLayers,
) -> Vec<Vec3> {
    let count = lights.names.len() + 1;
    let mut sent = vec![Vec3::ZERO; samples * count];
    let mut layers = vec![Vec3::ZERO; count - 1];
    for (chunk_points, log) in points.chunks(chunk).zip(terms) {
        for (index, point) in chunk_points.iter().enumerate() {
            layers.fill(Vec3::ZERO);
            let terms = log.log().map_or(&[][..], |log| log.point_terms(index));
            for &(light, value) in terms {
                layers[lights.layer_of[light as usize]] += value;
            }
            let at = point.sample as usize * count;
            for (sum, layer) in sent[at..at + count].iter_mut().zip(&layers) {
                *sum += point.weight * *layer;
            }
            sent[at + count - 1] += point.weight * job.environment.unlit(point);
        }
    }
    sent
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
