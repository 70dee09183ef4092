//! Shading points made on the GPU (`surface.wgsl`): from each path ray's
//! closest hit, the point, its normals, its texture coordinates and its
//! material with the base colour and emissive textures sampled there,
//! as `ShadingPoint::from_hit` makes them on the CPU. The scene's meshes,
//! materials and textures go up in flat form once per run; a frame's
//! placement (object maps, animated materials, deformed meshes) once per
//! frame.
//!
//! The points stay on the GPU for formula (1), the film and the Whitted
//! recursion; only `--method area` reads them back, to sample lamps.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Mat3, Vec3};

use super::context::{GpuContext, GpuError};
use super::contract::{
    DEFORMED, HITS, ITEMS, MATERIALS, MESHES, MESH_WORDS, NONE, OBJECTS, TEXELS, TEXTURES,
};
use super::pass::{answer_buffer, Bound, Dispatch, WorldPass, WorldUse};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::trace::HitRecord;
use crate::accel::{cofactor_map, Ray};
use crate::anim::deform::DeformedMesh;
use crate::render::frame::{FrameScene, PlacedObject};
use crate::render::material::SurfaceMaterial;
use crate::render::surface::ShadingPoint;
use crate::scene::{Material, SceneDesc, TextureRef, Wrap};

/// `path.wgsl`'s `PathRay`: a ray of a camera path, the pixel sample its
/// hit shades, the path's throughput and its Whitted depth.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PathRay {
    origin: [f32; 3],
    t_max: f32,
    direction: [f32; 3],
    sample: u32,
    weight: [f32; 3],
    depth: u32,
}

impl From<&Ray> for PathRay {
    /// `ray` as a camera ray of sample 0: a path of its own, for queries
    /// outside a frame.
    fn from(ray: &Ray) -> PathRay {
        PathRay::new(ray, 0, Vec3::ONE, 0)
    }
}

impl PathRay {
    pub fn new(ray: &Ray, sample: u32, weight: Vec3, depth: u32) -> PathRay {
        PathRay {
            origin: ray.origin.to_array(),
            t_max: ray.t_max,
            direction: ray.direction.to_array(),
            sample,
            weight: weight.to_array(),
            depth,
        }
    }
}

/// `surface_point.wgsl`'s `SurfacePoint`: a [`ShadingPoint`], or the
/// sample of a ray that hit nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SurfacePoint {
    position: [f32; 3],
    sample: u32,
    geometric_normal: [f32; 3],
    depth: u32,
    shading_normal: [f32; 3],
    front_face: u32,
    view: [f32; 3],
    hit: u32,
    weight: [f32; 3],
    metallic: f32,
    base_color: [f32; 3],
    roughness: f32,
    emissive: [f32; 3],
    specular: f32,
    transmission: f32,
    ior: f32,
    /// The point's index in its level, in a copy gathered for the CPU
    /// ([`super::light_mesh`]); 0 elsewhere.
    level_index: u32,
    _pad: u32,
}

impl SurfacePoint {
    /// The point's index in its level, in a copy gathered for the CPU.
    pub fn level_index(&self) -> u32 {
        self.level_index
    }

    /// The shading point, None for a miss.
    pub fn shading_point(&self) -> Option<ShadingPoint> {
        (self.hit != 0).then(|| ShadingPoint {
            sample: self.sample,
            weight: Vec3::from_array(self.weight),
            depth: self.depth,
            position: Vec3::from_array(self.position),
            geometric_normal: Vec3::from_array(self.geometric_normal),
            shading_normal: Vec3::from_array(self.shading_normal),
            front_face: self.front_face != 0,
            view: Vec3::from_array(self.view),
            material: SurfaceMaterial {
                base_color: Vec3::from_array(self.base_color),
                metallic: self.metallic,
                roughness: self.roughness,
                specular: self.specular,
                transmission: self.transmission,
                ior: self.ior,
                emissive: Vec3::from_array(self.emissive),
            },
        })
    }
}

impl From<&ShadingPoint> for SurfacePoint {
    fn from(point: &ShadingPoint) -> SurfacePoint {
        let m = &point.material;
        SurfacePoint {
            position: point.position.to_array(),
            sample: point.sample,
            geometric_normal: point.geometric_normal.to_array(),
            depth: point.depth,
            shading_normal: point.shading_normal.to_array(),
            front_face: point.front_face as u32,
            view: point.view.to_array(),
            hit: 1,
            weight: point.weight.to_array(),
            metallic: m.metallic,
            base_color: m.base_color.to_array(),
            roughness: m.roughness,
            emissive: m.emissive.to_array(),
            specular: m.specular,
            transmission: m.transmission,
            ior: m.ior,
            level_index: 0,
            _pad: 0,
        }
    }
}

/// `surface.wgsl`'s `MeshRecord`: where a mesh's arrays start in the
/// mesh words, and how many items each holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MeshRecord {
    indices: u32,
    triangle_count: u32,
    positions: u32,
    vertex_count: u32,
    normals: u32,
    normal_count: u32,
    uvs: u32,
    uv_count: u32,
    materials: u32,
    material_count: u32,
    _pad: [u32; 2],
}

/// `surface.wgsl`'s `TextureRecord`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct TextureRecord {
    texels: u32,
    width: u32,
    height: u32,
    wrap_s: u32,
    wrap_t: u32,
    _pad: [u32; 3],
}

/// `surface.wgsl`'s `ObjectRecord`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ObjectRecord {
    to_render: [[f32; 4]; 4],
    normal_to_render: [[f32; 4]; 3],
    cofactor: [[f32; 4]; 3],
    mesh: u32,
    deformed_positions: u32,
    deformed_normals: u32,
    deformed_normal_count: u32,
}

/// `surface.wgsl`'s `MaterialRecord`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialRecord {
    base_color: [f32; 4],
    emissive: [f32; 3],
    base_color_texture: u32,
    metallic: f32,
    roughness: f32,
    specular: f32,
    transmission: f32,
    ior: f32,
    emissive_texture: u32,
    _pad: [u32; 2],
}

impl From<&Material> for MaterialRecord {
    fn from(material: &Material) -> MaterialRecord {
        let texture = |slot: Option<TextureRef>| slot.map_or(NONE, |slot| slot.texture as u32);
        MaterialRecord {
            base_color: material.base_color.to_array(),
            emissive: material.emissive.to_array(),
            base_color_texture: texture(material.base_color_texture),
            metallic: material.metallic,
            roughness: material.roughness,
            specular: material.specular,
            transmission: material.transmission,
            ior: material.ior,
            emissive_texture: texture(material.emissive_texture),
            _pad: [0; 2],
        }
    }
}

/// The scene's meshes and textures on the GPU, uploaded once per run.
pub struct SceneSurfaces {
    meshes: wgpu::Buffer,
    words: wgpu::Buffer,
    textures: wgpu::Buffer,
    texels: wgpu::Buffer,
}

impl SceneSurfaces {
    pub fn upload(context: &GpuContext, scene: &SceneDesc) -> Result<SceneSurfaces, GpuError> {
        let mut words: Vec<u32> = Vec::new();
        let mut append = |items: &[u32]| {
            let offset = words.len() as u32;
            words.extend_from_slice(items);
            offset
        };
        let meshes: Vec<MeshRecord> = (scene.meshes.iter())
            .map(|mesh| MeshRecord {
                indices: append(bytemuck::cast_slice(&mesh.triangles)),
                triangle_count: mesh.triangles.len() as u32,
                positions: append(bytemuck::cast_slice(&mesh.positions)),
                vertex_count: mesh.positions.len() as u32,
                normals: append(bytemuck::cast_slice(&mesh.normals)),
                normal_count: mesh.normals.len() as u32,
                uvs: append(bytemuck::cast_slice(&mesh.uvs)),
                uv_count: mesh.uvs.len() as u32,
                materials: append(&mesh.triangle_materials),
                material_count: mesh.triangle_materials.len() as u32,
                _pad: [0; 2],
            })
            .collect();
        let mut texels = Vec::new();
        let textures: Vec<TextureRecord> = (scene.textures.iter())
            .map(|texture| {
                let record = TextureRecord {
                    texels: texels.len() as u32,
                    width: texture.width,
                    height: texture.height,
                    wrap_s: wrap_mode(texture.wrap_s),
                    wrap_t: wrap_mode(texture.wrap_t),
                    _pad: [0; 3],
                };
                texels.extend(texture.texels.iter().map(|texel| texel.to_array()));
                record
            })
            .collect();
        context.checked("uploading meshes and textures", || {
            Ok(SceneSurfaces {
                meshes: storage(context, "meshes", &meshes)?,
                words: storage(context, "mesh arrays", &words)?,
                textures: storage(context, "textures", &textures)?,
                texels: storage(context, "texels", &texels)?,
            })
        })
    }
}

fn wrap_mode(wrap: Wrap) -> u32 {
    match wrap {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    }
}

/// A frame's placement on the GPU: its objects, its materials as animated
/// (the default material last) and its deformed meshes; and what they were
/// made from, so that a frame placed as the last was uploads nothing (a
/// fly-through over still objects, or a still frame).
pub struct FrameSurfaces {
    objects: wgpu::Buffer,
    materials: wgpu::Buffer,
    deformed: wgpu::Buffer,
    placed: Placement,
}

/// The parts of a [`FrameScene`] the shading-point pass reads.
struct Placement {
    objects: Vec<PlacedObject>,
    materials: Vec<Material>,
    deformed: Vec<Option<Arc<DeformedMesh>>>,
}

impl Placement {
    fn of(frame: &FrameScene) -> Placement {
        Placement {
            objects: frame.objects.clone(),
            materials: frame.materials.clone(),
            deformed: frame.deformed.clone(),
        }
    }

    /// Whether `frame` places everything as this does; compared in place,
    /// so a still frame copies nothing.
    fn holds(&self, frame: &FrameScene) -> bool {
        self.objects == frame.objects
            && self.materials == frame.materials
            && self.deformed == frame.deformed
    }
}

impl FrameSurfaces {
    /// Brings `surfaces` up to `frame`, uploading only when its placement
    /// differs from the one uploaded.
    pub fn update<'s>(
        surfaces: &'s mut Option<FrameSurfaces>,
        context: &GpuContext,
        frame: &FrameScene,
    ) -> Result<&'s FrameSurfaces, GpuError> {
        if surfaces
            .as_ref()
            .is_some_and(|current| !current.placed.holds(frame))
        {
            *surfaces = None;
        }
        match surfaces {
            Some(current) => Ok(current),
            None => {
                let placed = Placement::of(frame);
                Ok(surfaces.insert(FrameSurfaces::upload(context, placed)?))
            }
        }
    }

    fn upload(context: &GpuContext, placed: Placement) -> Result<FrameSurfaces, GpuError> {
        let mut deformed: Vec<f32> = Vec::new();
        let objects: Vec<ObjectRecord> = (placed.objects.iter().zip(&placed.deformed))
            .map(|(object, mesh)| {
                let (positions, normals, normal_count) = match mesh {
                    Some(mesh) => {
                        let positions = deformed.len() as u32;
                        deformed.extend(mesh.positions.iter().flat_map(|p| p.to_array()));
                        let normals = deformed.len() as u32;
                        deformed.extend(mesh.normals.iter().flat_map(|n| n.to_array()));
                        (positions, normals, mesh.normals.len() as u32)
                    }
                    None => (NONE, NONE, 0),
                };
                ObjectRecord {
                    to_render: affine_columns(&object.to_render),
                    normal_to_render: mat3_columns(&object.normal_to_render),
                    cofactor: mat3_columns(&cofactor_map(&object.to_render)),
                    mesh: object.mesh as u32,
                    deformed_positions: positions,
                    deformed_normals: normals,
                    deformed_normal_count: normal_count,
                }
            })
            .collect();
        let materials: Vec<MaterialRecord> = (placed.materials.iter())
            .chain([&Material::default()])
            .map(MaterialRecord::from)
            .collect();
        context.checked("uploading the frame's objects", || {
            Ok(FrameSurfaces {
                objects: storage(context, "objects", &objects)?,
                materials: storage(context, "materials", &materials)?,
                deformed: storage(context, "deformed meshes", &deformed)?,
                placed,
            })
        })
    }
}

fn affine_columns(m: &Affine3A) -> [[f32; 4]; 4] {
    let column = |v: Vec3| v.extend(0.0).to_array();
    [
        column(m.matrix3.x_axis.into()),
        column(m.matrix3.y_axis.into()),
        column(m.matrix3.z_axis.into()),
        column(m.translation.into()),
    ]
}

fn mat3_columns(m: &Mat3) -> [[f32; 4]; 3] {
    let column = |v: Vec3| v.extend(0.0).to_array();
    [column(m.x_axis), column(m.y_axis), column(m.z_axis)]
}

/// The shading-point pipeline, made once per run.
pub struct SurfacePass {
    pub(super) pass: WorldPass,
}

impl SurfacePass {
    pub fn new(context: &GpuContext) -> SurfacePass {
        let inputs = [
            HITS, MESHES, MESH_WORDS, TEXTURES, TEXELS, OBJECTS, MATERIALS, DEFORMED,
        ];
        SurfacePass {
            pass: WorldPass::new(context, Entry::Surface, WorldUse::None, &inputs, &[]),
        }
    }

    /// Records the pass: a [`SurfacePoint`] into `level.points` for each
    /// of its path rays, from its closest hit.
    pub fn record(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        world: &GpuScene,
        scene: &SceneSurfaces,
        frame: &FrameSurfaces,
        level: &LevelBuffers,
    ) {
        let reads: [Bound; 9] = [
            (ITEMS, &level.paths),
            (HITS, &level.hits),
            (MESHES, &scene.meshes),
            (MESH_WORDS, &scene.words),
            (TEXTURES, &scene.textures),
            (TEXELS, &scene.texels),
            (OBJECTS, &frame.objects),
            (MATERIALS, &frame.materials),
            (DEFORMED, &frame.deformed),
        ];
        self.pass.record(
            context,
            encoder,
            level.dispatch(world),
            &reads,
            &level.points,
        );
    }
}

/// One batch of path rays on the GPU and what the passes make of them:
/// closest hits, shading points, and their direct light. Its buffers hold
/// `count` items; a level the compaction made holds as many as the GPU
/// wrote into `length`, which the CPU does not read.
pub struct LevelBuffers {
    pub count: usize,
    pub length: Option<wgpu::Buffer>,
    pub paths: wgpu::Buffer,
    pub hits: wgpu::Buffer,
    pub points: wgpu::Buffer,
}

impl LevelBuffers {
    /// Buffers for `paths`, uploaded.
    pub fn new(context: &GpuContext, paths: &[PathRay]) -> Result<LevelBuffers, GpuError> {
        let uploaded = storage(context, "path rays", paths)?;
        LevelBuffers::with_paths(context, uploaded, paths.len(), None)
    }

    /// Buffers for `count` path rays already in `paths` on the GPU, or
    /// for as many of them as `length` says where the GPU counted them.
    pub fn with_paths(
        context: &GpuContext,
        paths: wgpu::Buffer,
        count: usize,
        length: Option<wgpu::Buffer>,
    ) -> Result<LevelBuffers, GpuError> {
        Ok(LevelBuffers {
            count,
            length,
            paths,
            hits: answer_buffer::<HitRecord>(context, "closest hits", count)?,
            points: answer_buffer::<SurfacePoint>(context, "shading points", count)?,
        })
    }

    /// A dispatch over the level's rays or points, one invocation each.
    pub fn dispatch<'a>(&'a self, scene: &'a GpuScene) -> Dispatch<'a> {
        match &self.length {
            Some(length) => Dispatch::counted_on_gpu(scene, self.count, length),
            None => Dispatch::new(scene, self.count),
        }
    }
}
