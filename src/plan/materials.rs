//! Which materials call for secondary rays (mirror reflection, refraction),
//! by the very tests the Whitted recursion makes
//! ([`SurfaceMaterial::reflects`], [`SurfaceMaterial::transmits`]), in any
//! planned frame (materials can be animated), and whether the camera can
//! see a surface made of one.

use glam::Vec2;
use serde::Serialize;

use super::view::FrameView;
use super::PlannedFrames;
use crate::render::material::SurfaceMaterial;
use crate::scene::{Material, SceneDesc};

/// One material's part in the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialPlan {
    pub index: usize,
    pub name: Option<String>,
    /// A mirror in some planned frame (roughness below 0.1).
    pub reflects: bool,
    /// Refracts in some planned frame.
    pub transmits: bool,
    /// Some surface made of it may be seen in some planned frame.
    pub visible: bool,
    /// Both: the frames trace secondary rays from it.
    pub spawns_secondary: bool,
}

/// Whether the Whitted recursion traces a reflected or refracted ray from
/// `material`: the tests depend on its factors only (textures scale the
/// base and emissive colours, which they do not read).
pub fn spawns(material: &Material) -> (bool, bool) {
    let surface = SurfaceMaterial::at(material, &[], Vec2::ZERO);
    (surface.reflects(), surface.transmits())
}

/// The materials the triangles of `mesh` are made of (material 0 where a
/// triangle names none, as shading takes it).
pub fn mesh_materials(scene: &SceneDesc, mesh: usize) -> Vec<usize> {
    let mesh = &scene.meshes[mesh];
    let mut used: Vec<usize> = (mesh.triangle_materials.iter())
        .map(|&m| m as usize)
        .collect();
    if mesh.triangle_materials.len() < mesh.triangles.len() {
        used.push(0);
    }
    used.sort_unstable();
    used.dedup();
    used
}

/// Every material's plan, from the frames' materials and what `views` say
/// the camera may see.
pub fn plan(scene: &SceneDesc, planned: &PlannedFrames, views: &[FrameView]) -> Vec<MaterialPlan> {
    let mut plans: Vec<MaterialPlan> = (scene.materials.iter().enumerate())
        .map(|(index, material)| MaterialPlan {
            index,
            name: material.name.clone(),
            reflects: false,
            transmits: false,
            visible: false,
            spawns_secondary: false,
        })
        .collect();
    for ((_, placed), view) in planned.iter().zip(views) {
        for (plan, material) in plans.iter_mut().zip(&placed.materials) {
            let (reflects, transmits) = spawns(material);
            plan.reflects |= reflects;
            plan.transmits |= transmits;
        }
        for (object, _) in (placed.objects.iter().zip(&view.objects)).filter(|(_, &seen)| seen) {
            for material in mesh_materials(scene, object.mesh) {
                if let Some(plan) = plans.get_mut(material) {
                    plan.visible = true;
                }
            }
        }
    }
    for plan in &mut plans {
        plan.spawns_secondary = plan.visible && (plan.reflects || plan.transmits);
    }
    plans
}
