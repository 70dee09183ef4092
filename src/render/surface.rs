//! From a ray hit to a shading point: position, normals, texture
//! coordinates, the material evaluated there, and the direction back to the
//! viewer. Stage 1 and 2 of a frame produce these; every later stage reads
//! them.

use glam::{Vec2, Vec3};

use super::brdf::PointBrdf;
use super::frame::FrameScene;
use super::material::SurfaceMaterial;
use crate::accel::{Hit, Ray};
use crate::scene::SceneDesc;

/// A surface point that one camera path sees, with everything shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Index of the pixel sample this point contributes to.
    pub sample: u32,
    /// Path throughput: how much of this point's radiance reaches the
    /// sample (1 for primary hits, Fresnel-weighted after mirrors).
    pub weight: Vec3,
    /// Whitted recursion depth (0 for primary hits).
    pub depth: u32,
    pub position: Vec3,
    /// Unit geometric normal, turned towards the side the ray came from.
    pub geometric_normal: Vec3,
    /// Unit interpolated normal, in the same hemisphere as the geometric one.
    pub shading_normal: Vec3,
    /// Whether the ray hit the side the triangle's winding faces; tells a
    /// refracted ray whether it enters or leaves.
    pub front_face: bool,
    /// Unit direction from the point back along the incoming ray.
    pub view: Vec3,
    pub material: SurfaceMaterial,
}

impl ShadingPoint {
    /// The material's BRDF at this point, prepared for many lights. It is
    /// made where shading starts rather than stored: the points of a band
    /// are hundreds of megabytes, and this would be two fifths of them.
    pub fn brdf(&self) -> PointBrdf {
        PointBrdf::new(&self.material, self.shading_normal, self.view)
    }

    /// A primary hit on grey Lambertian matter, seen along its normal:
    /// what tests of lights and of the light mesh's sets ask of a point.
    #[cfg(test)]
    pub fn matte(position: Vec3, normal: Vec3) -> ShadingPoint {
        ShadingPoint {
            sample: 0,
            weight: Vec3::ONE,
            depth: 0,
            position,
            geometric_normal: normal,
            shading_normal: normal,
            front_face: true,
            view: normal,
            material: SurfaceMaterial {
                base_color: Vec3::splat(0.5),
                metallic: 0.0,
                roughness: 1.0,
                specular: 0.0,
                transmission: 0.0,
                ior: 1.5,
                emissive: Vec3::ZERO,
            },
        }
    }

    pub fn from_hit(
        scene: &SceneDesc,
        frame: &FrameScene,
        ray: &Ray,
        hit: &Hit,
        sample: u32,
        weight: Vec3,
        depth: u32,
    ) -> ShadingPoint {
        let object = &frame.objects[hit.object as usize];
        let mesh = &scene.meshes[object.mesh];
        let triangle = hit.triangle as usize;
        let [a, b, c] = mesh.triangles[triangle].map(|i| i as usize);
        let (u, v) = (hit.barycentric.x, hit.barycentric.y);
        let w = 1.0 - u - v;

        // The position comes from the barycentrics on the transformed
        // triangle, not from origin + t·direction: it lies on the surface to
        // within rounding, which the origin offsets are designed for.
        let deformed = frame.deformed[hit.object as usize].as_deref();
        let positions = deformed.map_or(&mesh.positions, |d| &d.positions);
        let normals = deformed.map_or(&mesh.normals, |d| &d.normals);
        let corner = |i: usize| object.to_render.transform_point3(positions[i]);
        let position = w * corner(a) + u * corner(b) + v * corner(c);

        let towards_viewer = -ray.direction.normalize();
        let front_face = hit.geometric_normal.dot(towards_viewer) >= 0.0;
        let geometric_normal = if front_face {
            hit.geometric_normal
        } else {
            -hit.geometric_normal
        };
        let shading_normal = match normals.get(a).zip(normals.get(b)).zip(normals.get(c)) {
            Some(((na, nb), nc)) => {
                let n =
                    (object.normal_to_render * (w * *na + u * *nb + v * *nc)).normalize_or_zero();
                if n.dot(geometric_normal) > 0.0 {
                    n
                } else if n == Vec3::ZERO {
                    geometric_normal
                } else {
                    -n
                }
            }
            None => geometric_normal,
        };
        let uv = match mesh.uvs.get(a).zip(mesh.uvs.get(b)).zip(mesh.uvs.get(c)) {
            Some(((ta, tb), tc)) => w * *ta + u * *tb + v * *tc,
            None => Vec2::ZERO,
        };
        let material_index = mesh.triangle_materials.get(triangle).copied().unwrap_or(0) as usize;
        let material = frame
            .materials
            .get(material_index)
            .map(|m| SurfaceMaterial::at(m, &scene.textures, uv))
            .unwrap_or_else(|| SurfaceMaterial::at(&Default::default(), &[], uv));
        ShadingPoint {
            sample,
            weight,
            depth,
            position,
            geometric_normal,
            shading_normal,
            front_face,
            view: towards_viewer,
            material,
        }
    }
}
