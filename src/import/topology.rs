//! Primitive topologies as triangle lists: TRIANGLES as is, strips and fans
//! unrolled with the winding rules of the glTF spec (section 3.7.2.1).

use gltf::mesh::Mode;

/// The triangles `mode` draws from `indices` (vertex indices of the
/// primitive), without the degenerate ones (two equal corners), which strips
/// use as restarts and which no ray can hit. Returns None for modes that draw
/// no triangles (points and lines).
pub fn triangles(mode: Mode, indices: &[u32]) -> Option<Vec<[u32; 3]>> {
    let corners = |i: usize| [indices[i], indices[i + 1], indices[i + 2]];
    let count = indices.len();
    let all: Vec<[u32; 3]> = match mode {
        Mode::Triangles => (0..count / 3).map(|t| corners(3 * t)).collect(),
        Mode::TriangleStrip => (0..count.saturating_sub(2))
            .map(|i| {
                let [a, b, c] = corners(i);
                if i % 2 == 0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..count.saturating_sub(1))
            .map(|i| [indices[i], indices[i + 1], indices[0]])
            .collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => return None,
    };
    Some(
        all.into_iter()
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_alternate_winding_so_all_faces_agree() {
        let strip = triangles(Mode::TriangleStrip, &[0, 1, 2, 3, 4]);
        assert_eq!(strip, Some(vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]));
    }

    #[test]
    fn fans_share_the_first_vertex() {
        let fan = triangles(Mode::TriangleFan, &[0, 1, 2, 3]);
        assert_eq!(fan, Some(vec![[1, 2, 0], [2, 3, 0]]));
    }

    #[test]
    fn restarts_and_a_ragged_tail_are_dropped() {
        let list = triangles(Mode::Triangles, &[0, 1, 2, 3, 3, 4, 5]);
        assert_eq!(list, Some(vec![[0, 1, 2]]));
        assert_eq!(triangles(Mode::Lines, &[0, 1]), None);
    }
}
