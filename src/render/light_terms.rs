//! Where an integrator puts each light's visible term at a shading point.
//! Formula (1), formula (2) and the lamp estimate are all sums over lights;
//! they hand each term, in light order, to a [`LightTerms`]. The beauty
//! needs only the sum (a `Vec3` is that sum); the `light` AOV needs the
//! terms themselves ([`TermLog`]), and gets the beauty's sum, bit for bit,
//! along with them.

use glam::Vec3;

/// A receiver of one point's light terms, in light order.
pub trait LightTerms {
    /// Light `light` (its index in the frame's lights) brings `value`.
    fn add(&mut self, light: usize, value: Vec3);
}

/// Light terms taken point after point by the shade stage, which asks
/// for each point's sum.
pub trait PointTerms: LightTerms + Default + Send {
    /// Starts the next point's terms.
    fn begin_point(&mut self);
    /// The current point's terms summed in light order.
    fn sum(&self) -> Vec3;
    /// Every point's terms, where they were kept.
    fn log(&self) -> Option<&TermLog>;
}

/// The sum of the terms: what the beauty needs.
impl LightTerms for Vec3 {
    #[inline]
    fn add(&mut self, _light: usize, value: Vec3) {
        *self += value;
    }
}

impl PointTerms for Vec3 {
    fn begin_point(&mut self) {
        *self = Vec3::ZERO;
    }

    fn sum(&self) -> Vec3 {
        *self
    }

    fn log(&self) -> Option<&TermLog> {
        None
    }
}

/// Points' light terms kept one by one, point after point, with each
/// point's sum.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TermLog {
    /// The current point's sum, the same bits as a `Vec3`'s.
    pub sum: Vec3,
    /// (light, value) of every term of every point begun so far.
    pub terms: Vec<(u32, Vec3)>,
    /// Where each point's terms start in `terms`.
    pub starts: Vec<u32>,
}

impl TermLog {
    /// The terms of the `point`-th point begun.
    pub fn point_terms(&self, point: usize) -> &[(u32, Vec3)] {
        let start = self.starts[point] as usize;
        let end = (self.starts.get(point + 1)).map_or(self.terms.len(), |&end| end as usize);
        &self.terms[start..end]
    }
}

impl LightTerms for TermLog {
    fn add(&mut self, light: usize, value: Vec3) {
        self.sum += value;
        self.terms.push((light as u32, value));
    }
}

impl PointTerms for TermLog {
    fn begin_point(&mut self) {
        self.sum = Vec3::ZERO;
        self.starts.push(self.terms.len() as u32);
    }

    fn sum(&self) -> Vec3 {
        self.sum
    }

    fn log(&self) -> Option<&TermLog> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_keeps_each_points_terms_and_the_sums_bits() {
        let values = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::splat(1e-8),
            Vec3::splat(3.0),
        ];
        let mut sum = Vec3::ZERO;
        let mut log = TermLog::default();
        log.begin_point();
        for (light, &value) in values.iter().enumerate() {
            sum.add(light, value);
            log.add(light, value);
        }
        assert_eq!(log.sum, sum);
        log.begin_point();
        log.begin_point();
        log.add(7, Vec3::ONE);
        assert_eq!(log.point_terms(0).len(), 3);
        assert!(log.point_terms(1).is_empty());
        assert_eq!(log.point_terms(2), &[(7, Vec3::ONE)]);
        assert_eq!(log.sum, Vec3::ONE);
    }
}
