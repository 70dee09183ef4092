//! The light mesh a sequence keeps from frame to frame, and from run to run
//! through the disk cache ([`super::cache`]). It is made on the first frame
//! that shades from it (`h` from the settings or the lamp radii, see
//! [`super::spacing`]) and seeded then with the static bits the disk cache
//! holds for where the lights stand; between frames, invalidation drops
//! only the bits that changed geometry or moved lights can have changed
//! ([`super::invalidate`]); after the last frame the static bits are saved
//! back. A light that leaves its starting position would take the bits the
//! next run starts from with it, so those are kept aside before they are
//! dropped and saved too.
//!
//! In the frame loop: `Sequence::advance` calls [`PersistentLightMesh::invalidate`],
//! `Sequence::render` calls [`PersistentLightMesh::prepare`] and hands the
//! light mesh to the backend, and the run ends with
//! [`PersistentLightMesh::save`].

use std::path::PathBuf;
use std::time::Instant;

use super::cache::{static_geometry_hash, LightKey, StaticMaskCache};
use super::invalidate::ChangedRegion;
use super::lattice::Lattice;
use super::{spacing, LightMesh, LightMeshError};
use crate::output::OutputError;
use crate::render::frame::FrameScene;
use crate::render::light::RenderLight;
use crate::scene::SceneDesc;
use crate::settings::LightMeshSettings;

/// What loading the disk cache gave a light mesh, and what it took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CacheLoad {
    pub bits: u64,
    /// Reading, checking and importing the file.
    pub seconds: f64,
}

/// A sequence's light mesh, once a frame has made it, with what its disk
/// cache needs to load and save the static masks.
pub struct PersistentLightMesh {
    mesh: Option<LightMesh>,
    /// Content hash of the static geometry, part of the disk cache's key.
    static_geometry: u128,
    /// Where the static masks are loaded from and saved to; None (the
    /// default for sequences made in code) uses no disk cache.
    cache_dir: Option<PathBuf>,
    /// What the disk cache gave the light mesh, not yet reported.
    loaded: CacheLoad,
    /// Where each light stood when the light mesh was made, and the static
    /// bits of those positions, kept when the light moved away, to save.
    cache_start: Vec<LightKey>,
    cache_kept: StaticMaskCache,
}

impl PersistentLightMesh {
    /// No light mesh yet, for the scene `scene` as `placed` (at rest)
    /// places its static objects: they name the disk cache's file.
    pub fn new(scene: &SceneDesc, placed: &FrameScene) -> PersistentLightMesh {
        let static_objects = (placed.objects.iter().enumerate())
            .filter(|(_, object)| !object.dynamic)
            .map(|(index, object)| {
                let mesh = &scene.meshes[object.mesh];
                (
                    index,
                    &mesh.positions[..],
                    &mesh.triangles[..],
                    object.to_render,
                )
            });
        PersistentLightMesh {
            mesh: None,
            static_geometry: static_geometry_hash(static_objects),
            cache_dir: None,
            loaded: CacheLoad::default(),
            cache_start: Vec::new(),
            cache_kept: StaticMaskCache::default(),
        }
    }

    /// Uses `dir` as the disk cache of static masks, or none. Takes effect
    /// when the light mesh is made.
    pub fn set_cache_dir(&mut self, dir: Option<PathBuf>) {
        self.cache_dir = dir;
    }

    /// The content hash of the static geometry (the disk cache's key).
    pub fn static_geometry(&self) -> u128 {
        self.static_geometry
    }

    /// The light mesh, once a frame has made it.
    pub fn get(&self) -> Option<&LightMesh> {
        self.mesh.as_ref()
    }

    /// The light mesh for a frame whose lights are `lights`, made on first
    /// use from `settings` for a scene of `scene_radius` metres around the
    /// render-space origin, and then loaded from the disk cache. Later
    /// calls return it as the last frame left it.
    pub fn prepare(
        &mut self,
        lights: &[RenderLight],
        settings: &LightMeshSettings,
        scene_radius: f32,
    ) -> Result<&mut LightMesh, LightMeshError> {
        if let Some(mesh) = self.mesh.take() {
            return Ok(self.mesh.insert(mesh));
        }
        let ki = settings.ki;
        let h = settings.h.unwrap_or_else(|| {
            spacing::default_h(lights, ki, settings.coarseness, 2.0 * scene_radius)
        });
        let lattice = Lattice::new(h);
        let reach = scene_radius + ki * h;
        if !lattice.covers(glam::Vec3::ZERO, reach) {
            return Err(LightMeshError::OutOfRange { h, distance: reach });
        }
        let limit = settings.max_memory_mib.saturating_mul(1 << 20);
        let mut mesh = LightMesh::new(lattice, ki, lights.len(), limit);
        mesh.kernel = settings.kernel;
        mesh.penumbra = settings.penumbra;
        mesh.faint_parts = super::faint::budget_parts(settings.faint_lamps);
        if let Some(dir) = &self.cache_dir {
            let start = Instant::now();
            let bits = mesh.load_static_masks(dir, self.static_geometry, lights);
            self.loaded = CacheLoad {
                bits,
                seconds: start.elapsed().as_secs_f64(),
            };
            self.cache_start = lights.iter().map(LightKey::of).collect();
        }
        Ok(self.mesh.insert(mesh))
    }

    /// What the disk cache gave the light mesh since the last call:
    /// reported with the stats of the frame that made it.
    pub fn take_load(&mut self) -> CacheLoad {
        std::mem::take(&mut self.loaded)
    }

    /// Brings the light mesh from the frame whose lights were `before` to
    /// one whose lights are `after`: drops the bits that geometry changes
    /// in `regions` and the moves of `moved_lights` can have changed, after
    /// keeping for the disk cache the static bits of lights that leave
    /// their starting position. Returns how many valid bits were dropped
    /// (none without a light mesh).
    pub fn invalidate(
        &mut self,
        before: Option<&[RenderLight]>,
        after: &[RenderLight],
        regions: &[ChangedRegion],
        moved_lights: &[usize],
    ) -> u64 {
        let Some(mesh) = &mut self.mesh else {
            return 0;
        };
        if let (Some(_), Some(before)) = (&self.cache_dir, before) {
            let start = &self.cache_start;
            let leaving = (moved_lights.iter().copied())
                .filter(|&light| start.get(light) == Some(&LightKey::of(&before[light])));
            mesh.keep_static_masks(&mut self.cache_kept, before, leaving);
        }
        mesh.invalidate(regions, moved_lights, after)
    }

    /// Saves the light mesh's static masks to the disk cache, merged with
    /// what other workers saved there: for `lights` (where the last frame
    /// placed them), and where they stood when the light mesh was made.
    /// Does nothing without a cache directory or a light mesh.
    pub fn save(&self, lights: &[RenderLight]) -> Result<(), OutputError> {
        match (&self.cache_dir, &self.mesh) {
            (Some(dir), Some(mesh)) => {
                mesh.save_static_masks(dir, self.static_geometry, lights, &self.cache_kept)
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};

    use super::*;
    use crate::render::frame::CameraChoice;
    use crate::render::light::LightSource;
    use crate::scene::pose::Pose;
    use crate::scene::{Camera, Node, Projection};

    /// Nothing to cast shadows on, seen by a camera, so that it places.
    fn empty() -> PersistentLightMesh {
        let scene = SceneDesc {
            nodes: vec![Node {
                camera: Some(0),
                ..Node::default()
            }],
            roots: vec![0],
            cameras: vec![Camera {
                name: None,
                projection: Projection::Orthographic {
                    xmag: 1.0,
                    ymag: 1.0,
                    znear: 0.0,
                    zfar: 10.0,
                },
            }],
            ..SceneDesc::default()
        };
        let rest = Pose::rest(&scene);
        let choice = CameraChoice::First;
        let placed = FrameScene::place(
            &scene,
            &rest,
            DVec3::ZERO,
            choice,
            &Default::default(),
            &crate::scene::pose::dynamic_nodes(&scene),
        )
        .unwrap();
        PersistentLightMesh::new(&scene, &placed)
    }

    fn lamp() -> Vec<RenderLight> {
        vec![RenderLight {
            source: LightSource::Point {
                position: Vec3::new(0.0, 5.0, 0.0),
            },
            power: Vec3::ONE,
            range: None,
            lamp_radius: 0.1,
        }]
    }

    fn with_h(h: f32) -> LightMeshSettings {
        LightMeshSettings {
            h: Some(h),
            ..LightMeshSettings::default()
        }
    }

    #[test]
    fn the_first_frame_makes_the_light_mesh_and_later_frames_reuse_it() {
        let mut kept = empty();
        assert!(kept.get().is_none());
        assert_eq!(kept.invalidate(None, &lamp(), &[], &[0]), 0);
        assert_eq!(
            kept.prepare(&lamp(), &with_h(0.5), 10.0).unwrap().lattice.h,
            0.5
        );
        // Other settings later change nothing: the masks stay those of the
        // lattice they were computed on.
        assert_eq!(
            kept.prepare(&lamp(), &with_h(0.25), 10.0)
                .unwrap()
                .lattice
                .h,
            0.5
        );
        assert_eq!(kept.get().map(|mesh| mesh.lattice.h), Some(0.5));
        assert_eq!(kept.take_load().bits, 0);
    }

    #[test]
    fn a_lattice_too_fine_for_the_scene_is_refused_and_nothing_is_kept() {
        let mut kept = empty();
        let error = kept.prepare(&lamp(), &with_h(1e-6), 1e5).unwrap_err();
        assert!(
            matches!(error, LightMeshError::OutOfRange { .. }),
            "{error}"
        );
        assert!(kept.get().is_none());
    }

    #[test]
    fn without_a_cache_directory_nothing_is_saved() {
        let mut kept = empty();
        kept.prepare(&lamp(), &with_h(0.5), 10.0).unwrap();
        kept.save(&lamp()).unwrap();
    }
}
