//! Which nodes a point's wide set holds (`super::wide`): the half-ball of
//! radius 2·kI·h on the lattice of step 2h, whose nodes are mesh nodes,
//! and the lights it is asked about (lamps). The demand asks for these
//! nodes' bits and the wide set reads them, so both take them from here.

use glam::{IVec3, Vec3};

use super::lattice::{Lattice, MAX_NODE_COORDINATE};
use super::LightMesh;
use crate::render::light::RenderLight;

/// Mesh steps per step of the wide set's lattice.
pub const STEPS: i32 = 2;
// A wide node's mesh coordinates stay in range.
const _: () = assert!(MAX_NODE_COORDINATE * (STEPS as f32) < i32::MAX as f32);

/// The wide set's half-ball: its lattice (the mesh's origin, step 2h) and
/// radius (2·kI·h).
#[derive(Clone, Copy, Debug)]
pub struct WideBall {
    pub lattice: Lattice,
    pub radius: f32,
}

impl WideBall {
    pub fn of(mesh: &LightMesh) -> WideBall {
        WideBall::around(mesh.lattice, mesh.ki)
    }

    /// The wide set's half-ball for a mesh on `lattice` whose
    /// interpolation radius is `ki` steps.
    pub fn around(lattice: Lattice, ki: f32) -> WideBall {
        let lattice = Lattice {
            origin: lattice.origin,
            h: lattice.h * STEPS as f32,
        };
        WideBall {
            lattice,
            radius: ki * lattice.h,
        }
    }

    /// Appends to `out` the mesh nodes of the wide half-ball of the point
    /// at `p` with normal `n`. A wide node's position is its mesh node's to
    /// the bit (2h·i and h·2i round alike: scaling by two is exact).
    pub fn nodes(&self, p: Vec3, n: Vec3, out: &mut Vec<IVec3>) {
        let first = out.len();
        self.lattice.half_ball(p, n, self.radius, out);
        for node in &mut out[first..] {
            *node *= STEPS;
        }
    }
}

/// A bit per light that has a lamp to size a penumbra by (a point or spot
/// light of positive radius), in `words` words.
pub fn lamps(lights: &[RenderLight], words: usize) -> Vec<u64> {
    let mut bits = vec![0; words];
    for (index, light) in lights.iter().enumerate() {
        if light.position().is_some() && light.lamp_radius > 0.0 {
            bits[index / 64] |= 1 << (index % 64);
        }
    }
    bits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::LightSource;

    const H: f32 = 0.1;

    #[test]
    fn wide_nodes_are_mesh_nodes_where_the_wide_lattice_puts_them() {
        let wide = WideBall::around(Lattice::new(H), 2.5);
        let mesh = Lattice::new(H);
        let mut nodes = vec![IVec3::MAX];
        let p = Vec3::new(0.31, -0.07, 1e3);
        wide.nodes(p, Vec3::new(0.2, 1.0, -0.3).normalize(), &mut nodes);
        assert_eq!(nodes[0], IVec3::MAX, "appended after what was there");
        let mut own = Vec::new();
        wide.lattice.half_ball(
            p,
            Vec3::new(0.2, 1.0, -0.3).normalize(),
            wide.radius,
            &mut own,
        );
        assert_eq!(nodes.len(), own.len() + 1);
        assert!(own.len() > 20, "{} nodes", own.len());
        for (&node, &level_node) in nodes[1..].iter().zip(&own) {
            assert_eq!(node, level_node * 2);
            let (at_mesh, at_level) = (
                mesh.node_position(node),
                wide.lattice.node_position(level_node),
            );
            assert_eq!(
                at_mesh.to_array().map(f32::to_bits),
                at_level.to_array().map(f32::to_bits)
            );
        }
    }

    #[test]
    fn only_reaching_lamps_count_and_directional_lights_are_no_lamps() {
        let light = |source, lamp_radius| RenderLight {
            source,
            power: Vec3::ONE,
            range: None,
            lamp_radius,
        };
        let point = LightSource::Point {
            position: Vec3::ZERO,
        };
        let sun = LightSource::Directional { towards: Vec3::Y };
        let mut lights = vec![light(point, 0.0); 70];
        lights[3] = light(point, 0.2);
        lights[5] = light(sun, 0.2);
        lights[66] = light(point, 0.1);
        assert_eq!(lamps(&lights, 2), vec![1 << 3, 1 << 2]);
    }
}
