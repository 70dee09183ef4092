//! The lamps a point leaves at the half-ball's answer: the faint ones.
//!
//! `penumbra: blocker` and `wide` refine a lamp's share at a point with
//! rays (the blocker's, the grazing probe's, a level's node segments), one
//! set per (point, lamp) pair, so they scale like Whitted's shadow rays.
//! On a street of 64 lamps most of those pairs are far lamps that bring a
//! point almost nothing. Refining a lamp moves its term by at most the
//! term itself (a share stays within [0, 1]), so a point may leave a set
//! of lamps at the answer `fixed` gives (the half-ball's share; full where
//! every node sees the lamp) if their unshadowed terms add up to at most a
//! share ε (`lightmesh.faint_lamps`) of the point's unshadowed lamp light.
//! The point's light then moves by at most ε of its unshadowed light,
//! which is the denominator of STUDY.md's error, so ε bounds what the rule
//! adds to a pixel's error there; ε = 0 refines every lamp.
//!
//! The rule is integer arithmetic on the bits of each lamp's term (its
//! largest channel, a positive normal f32), so that the GPU's shader
//! (`light_mesh.wgsl`) skips the same lamps and the frames keep their
//! bits whatever order either side adds in:
//! - E is the largest exponent among the point's lamps. A lamp of exponent
//!   e and significand m (24 bits, the implicit one included) brings
//!   m / 2^(E−e) in units of 2^(E−150), so the brightest brings ≥ 2^23.
//! - Bucket d = min(E − e, [`LAST_BUCKET`]) holds the sum of its lamps'
//!   m (saturating). Bucket d's light is at most ⌈sum / 2^d⌉ (the last
//!   bucket's lamps, each under 2^24 / 2^d, too), and at least ⌊sum / 2^d⌋
//!   for every bucket but the last.
//! - The point's light, rounded down, is the buckets' floors, the last left
//!   out; the budget is that over 2^16 times ⌊ε·2^16⌋ ([`budget_parts`]).
//! - Buckets are skipped from the faintest towards the brightest while the
//!   skipped light, rounded up, stays within the budget; bucket 0 never is.
//!
//! Lamps whose term's exponent field is zero (none, or subnormal: a GPU
//! may flush those) take no part and are never faint.

use crate::bits::set_bits;
use crate::render::omega::OmegaBlock;

/// Buckets 0 to `LAST_BUCKET`: lamps 2^24 times fainter than the brightest
/// and beyond share the last.
pub const LAST_BUCKET: u32 = 24;
/// Buckets in all.
pub const BUCKETS: usize = LAST_BUCKET as usize + 1;
/// The first bucket no lamp is in: what [`FaintLamps::faintest_kept`] is
/// when none is faint.
pub const NO_FAINT_BUCKET: u32 = LAST_BUCKET + 1;
/// ε is applied in steps of 2^-16.
pub const BUDGET_BITS: u32 = 16;
/// The largest ε: the budget's product stays within 32 bits.
pub const MAX_FAINT_SHARE: f32 = 0.5;

/// ⌊ε·2^16⌋ for `share` = ε in [0, [`MAX_FAINT_SHARE`]]: the budget's
/// factor, which the GPU receives as it is.
pub fn budget_parts(share: f32) -> u32 {
    (share.clamp(0.0, MAX_FAINT_SHARE) * (1 << BUDGET_BITS) as f32) as u32
}

/// The exponent field of a lamp's term (its largest channel), 0 where it
/// takes no part in the rule.
pub fn exponent(term: f32) -> u32 {
    term.to_bits() >> 23 & 0xff
}

/// The 24-bit significand of a normal term.
fn significand(term: f32) -> u32 {
    term.to_bits() & 0x7f_ffff | 0x80_0000
}

/// The faint lamps of one point, found from its lamps' terms: their
/// largest exponent field ([`FaintLamps::brightest`]), then their
/// significands into buckets (`add_sum`), then
/// [`FaintLamps::faintest_kept`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaintLamps {
    /// E, the largest exponent field (0 for a point with no lamp light).
    brightest: u32,
    /// Per bucket, its lamps' significands summed, saturating.
    buckets: [u32; BUCKETS],
    /// The faintest bucket a lamp is in: those past it are empty, so the
    /// rule's loops stop there.
    faintest: u32,
}

impl FaintLamps {
    /// Ready to count lamps into buckets at a point whose brightest lamp
    /// term has exponent field `brightest` (the largest [`exponent`]).
    pub fn brightest(brightest: u32) -> FaintLamps {
        FaintLamps {
            brightest,
            buckets: [0; BUCKETS],
            faintest: 0,
        }
    }

    /// Counts lamps whose terms have exponent field `exponent` and whose
    /// significands sum to `sum` (saturating) into their bucket. Sums of
    /// non-negative integers saturate to the same value however they are
    /// grouped, so lamps may be summed per exponent first.
    fn add_sum(&mut self, exponent: u32, sum: u32) {
        if exponent == 0 {
            return;
        }
        let bucket = (self.brightest - exponent).min(LAST_BUCKET);
        let into = &mut self.buckets[bucket as usize];
        *into = into.saturating_add(sum);
        self.faintest = self.faintest.max(bucket);
    }

    /// The first bucket whose lamps are faint under the budget of
    /// `parts` ([`budget_parts`]): a lamp is faint where its bucket is at
    /// least this; [`NO_FAINT_BUCKET`] where none is. An empty bucket
    /// adds nothing to the light or to what is skipped, so the loops stop
    /// at the faintest lamp's bucket: every bucket past it is skipped
    /// within any budget.
    pub fn faintest_kept(&self, parts: u32) -> u32 {
        let faintest = self.faintest;
        let light = (0..=faintest.min(LAST_BUCKET - 1))
            .map(|bucket| self.buckets[bucket as usize] >> bucket)
            .fold(0u32, u32::saturating_add);
        let budget = (light >> BUDGET_BITS) * parts;
        let mut skipped = 0u32;
        let mut first_faint = faintest + 1;
        for bucket in (1..=faintest).rev() {
            skipped = skipped.saturating_add(rounded_up(self.buckets[bucket as usize], bucket));
            if skipped > budget {
                break;
            }
            first_faint = bucket;
        }
        first_faint
    }
}

/// Exponent fields of an f32.
const EXPONENTS: usize = 256;

/// One point's lamps, gathered a block of lights at a time as demand
/// evaluates their terms ([`LampTerms::add`]), then sorted into faint and
/// kept ([`LampTerms::mark`]). A lamp's term is its Omega's largest
/// channel, as formula (2) will weigh it. Lamps are kept by their term's
/// exponent field, the one thing the rule tells them apart by: per field,
/// the sum of their significands and a bit per lamp, so a point costs a
/// few operations per lamp and per field its lamps span, with no list to
/// walk again. One per thread, reused from point to point.
pub struct LampTerms {
    words: usize,
    /// Per exponent field, its lamps' significands summed, saturating.
    sums: [u32; EXPONENTS],
    /// Per exponent field, `words` words: its lamps, a bit per light.
    lamps: Vec<u64>,
    /// The fields this point's lamps span (empty: `lowest` > `highest`).
    lowest: usize,
    highest: usize,
}

impl LampTerms {
    /// For frames of `words` words of 64 lights.
    pub fn new(words: usize) -> LampTerms {
        LampTerms {
            words,
            sums: [0; EXPONENTS],
            lamps: vec![0; EXPONENTS * words],
            lowest: EXPONENTS,
            highest: 0,
        }
    }

    /// Ready for the next point: clears the fields the last one used.
    pub fn clear(&mut self) {
        if self.lowest <= self.highest {
            self.sums[self.lowest..=self.highest].fill(0);
            self.lamps[self.lowest * self.words..(self.highest + 1) * self.words].fill(0);
        }
        (self.lowest, self.highest) = (EXPONENTS, 0);
    }

    /// Adds the lamps of `lanes` (a bit per lane of the block whose first
    /// light is `first`) that bring the point light, with their terms
    /// from `omega`.
    #[inline]
    pub fn add(&mut self, first: usize, lanes: u8, omega: &OmegaBlock) {
        for lane in set_bits((lanes & omega.reaching).into()) {
            self.add_lamp(first + lane, omega.get(lane).max_element());
        }
    }

    /// Adds lamp number `light`, whose term is `term`.
    fn add_lamp(&mut self, light: usize, term: f32) {
        let field = exponent(term) as usize;
        if field == 0 {
            return; // takes no part, never faint
        }
        self.sums[field] = self.sums[field].saturating_add(significand(term));
        self.lamps[field * self.words + light / 64] |= 1 << (light % 64);
        self.lowest = self.lowest.min(field);
        self.highest = self.highest.max(field);
    }

    /// Sets in `faint` (a bit per light, 64 to a word) the faint lamps
    /// among those added, under the budget of `parts` ([`budget_parts`]).
    pub fn mark(&self, parts: u32, faint: &mut [u64]) {
        faint.fill(0);
        if parts == 0 || self.lowest > self.highest {
            return;
        }
        let mut buckets = FaintLamps::brightest(self.highest as u32);
        for field in self.lowest..=self.highest {
            buckets.add_sum(field as u32, self.sums[field]);
        }
        let first_faint = buckets.faintest_kept(parts);
        if first_faint == NO_FAINT_BUCKET {
            return;
        }
        // A lamp of field e is in bucket min(E − e, LAST_BUCKET), so it is
        // faint where E − e reaches the first faint bucket (at most the
        // last).
        let Some(brightest_faint) = self.highest.checked_sub(first_faint as usize) else {
            return;
        };
        for field in self.lowest..=brightest_faint {
            let lamps = &self.lamps[field * self.words..(field + 1) * self.words];
            for (faint, lamps) in faint.iter_mut().zip(lamps) {
                *faint |= lamps;
            }
        }
    }
}

/// ⌈sum / 2^`bucket`⌉, for `bucket` ≤ [`LAST_BUCKET`].
fn rounded_up(sum: u32, bucket: u32) -> u32 {
    (sum >> bucket) + u32::from(sum & ((1 << bucket) - 1) != 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The faint flags of `terms` under `share` by the rule as the module
    /// states it, lamp by lamp into buckets: the model both
    /// [`LampTerms`] and the GPU's `faint.wgsl` must agree with.
    fn faint(terms: &[f32], share: f32) -> Vec<bool> {
        let brightest = terms.iter().map(|&t| exponent(t)).max().unwrap_or(0);
        let mut lamps = FaintLamps::brightest(brightest);
        (terms.iter()).for_each(|&term| lamps.add_sum(exponent(term), significand(term)));
        let first = lamps.faintest_kept(budget_parts(share));
        assert_eq!(
            first,
            faintest_kept_over_every_bucket(&lamps, budget_parts(share))
        );
        let bucket = |term: f32| (brightest - exponent(term)).min(LAST_BUCKET);
        (terms.iter())
            .map(|&term| exponent(term) != 0 && bucket(term) >= first)
            .collect()
    }

    /// [`FaintLamps::faintest_kept`] as the module states the rule, over
    /// every bucket: the first faint bucket is the brightest one from
    /// which every fainter bucket, rounded up, fits within the budget
    /// (those sums only grow towards the brightest). What stopping at the
    /// faintest lamp's bucket must not change.
    fn faintest_kept_over_every_bucket(lamps: &FaintLamps, parts: u32) -> u32 {
        let light_of = |bucket: u32| lamps.buckets[bucket as usize] >> bucket;
        let light = (0..LAST_BUCKET).map(light_of).fold(0, u32::saturating_add);
        let budget = (light >> BUDGET_BITS) * parts;
        let skipped_from = |first: u32| {
            (first..=LAST_BUCKET)
                .map(|bucket| rounded_up(lamps.buckets[bucket as usize], bucket))
                .fold(0, u32::saturating_add)
        };
        (1..=LAST_BUCKET)
            .find(|&first| skipped_from(first) <= budget)
            .unwrap_or(NO_FAINT_BUCKET)
    }

    /// The faint flags [`LampTerms`] marks for `terms` (lamp i's term at
    /// light `lights[i]`), after it served another point.
    fn marked(terms: &[f32], lights: &[usize], share: f32, words: usize) -> Vec<bool> {
        let mut lamps = LampTerms::new(words);
        lamps.add_lamp(0, 1.0);
        lamps.add_lamp(words * 64 - 1, 1e-30);
        lamps.clear();
        (lights.iter().zip(terms)).for_each(|(&light, &term)| lamps.add_lamp(light, term));
        let mut faint = vec![!0; words];
        lamps.mark(budget_parts(share), &mut faint);
        (lights.iter())
            .map(|&light| faint[light / 64] >> (light % 64) & 1 == 1)
            .collect()
    }

    #[test]
    fn far_lamps_are_faint_and_near_ones_are_not() {
        // One near lamp and three a hundred times fainter: together 3% of
        // the light, under a budget of 1/16.
        let terms = [1.0, 0.01, 0.01, 0.01];
        assert_eq!(faint(&terms, 1.0 / 16.0), [false, true, true, true]);
        // Under 1/64 only those rounding shows to be within it.
        assert_eq!(faint(&terms, 1.0 / 64.0), [false; 4]);
        // ε = 0 refines every lamp.
        assert_eq!(faint(&terms, 0.0), [false; 4]);
    }

    #[test]
    fn the_faintest_lamps_own_light_counts_towards_the_budget() {
        // Two lamps half as bright as the brightest bring half the light:
        // exactly the largest share, counted with their own light.
        assert_eq!(
            faint(&[1.0, 0.5, 0.5], MAX_FAINT_SHARE),
            [false, true, true]
        );
        assert_eq!(faint(&[1.0, 0.5, 0.5, 0.5], MAX_FAINT_SHARE), [false; 4]);
    }

    #[test]
    fn equal_lamps_and_a_lone_lamp_are_never_faint() {
        assert_eq!(faint(&[0.3; 8], MAX_FAINT_SHARE), [false; 8]);
        assert_eq!(faint(&[1e-30], MAX_FAINT_SHARE), [false]);
        assert_eq!(faint(&[], MAX_FAINT_SHARE), Vec::<bool>::new());
    }

    #[test]
    fn a_faintest_bucket_over_the_budget_leaves_every_lamp_kept() {
        // 300 lamps 2^100 times fainter than the brightest share the last
        // bucket, whose light, rounded up, is over the budget.
        let mut terms = vec![1.0];
        terms.extend([1e-30; 300]);
        let share = 1.0 / 65536.0;
        assert_eq!(faint(&terms, share), [false; 301]);
        let lights: Vec<usize> = (0..terms.len()).collect();
        assert_eq!(marked(&terms, &lights, share, 5), [false; 301]);
    }

    #[test]
    fn subnormal_and_zero_terms_take_no_part() {
        let terms = [1.0, 0.0, f32::from_bits(1), 1e-9];
        assert_eq!(faint(&terms, 1.0 / 16.0), [false, false, false, true]);
    }

    #[test]
    fn huge_counts_of_huge_terms_saturate_without_skipping_the_brightest() {
        let mut terms = vec![f32::MAX; 300];
        terms.extend([1e-20; 300]);
        let flags = faint(&terms, MAX_FAINT_SHARE);
        assert!(flags[..300].iter().all(|&faint| !faint));
        assert!(flags[300..].iter().all(|&faint| faint));
    }

    proptest! {
        /// Lamps kept by exponent field mark what the rule marks lamp by
        /// lamp, over five words of lights in any order, through
        /// saturated sums, zero and subnormal terms, and with a previous
        /// point's fields cleared.
        #[test]
        fn lamp_terms_mark_what_the_rule_marks(
            terms in prop::collection::vec(
                prop_oneof![
                    Just(0.0f32),
                    Just(f32::from_bits(3)),
                    Just(f32::MAX),
                    1e-38f32..1e-20,
                    1e-12f32..1e-6,
                    1e-6f32..1e-2,
                    1e-2f32..10.0,
                ],
                0..300,
            ),
            seed in any::<u64>(),
            share in 0.0f32..=MAX_FAINT_SHARE,
        ) {
            let mut lights: Vec<usize> = (0..terms.len()).collect();
            let mut state = seed | 1;
            for i in (1..lights.len()).rev() {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                lights.swap(i, (state % (i as u64 + 1)) as usize);
            }
            let words = 5;
            prop_assert_eq!(marked(&terms, &lights, share, words), faint(&terms, share));
        }

        /// The bound the rule exists for: the faint lamps' terms add up to
        /// at most ε of all the terms, and the brightest is never faint.
        #[test]
        fn faint_lamps_bring_at_most_the_share(
            terms in prop::collection::vec(
                prop_oneof![1e-12f32..1e-6, 1e-6f32..1e-2, 1e-2f32..10.0], 1..80),
            share in 0.0f32..=MAX_FAINT_SHARE,
        ) {
            let flags = faint(&terms, share);
            let total: f64 = terms.iter().map(|&t| t as f64).sum();
            let skipped: f64 = (terms.iter().zip(&flags))
                .filter(|(_, &faint)| faint)
                .map(|(&t, _)| t as f64)
                .sum();
            prop_assert!(skipped <= share as f64 * total, "{skipped} of {total}");
            let brightest = terms.iter().cloned().fold(0.0f32, f32::max);
            let at = terms.iter().position(|&t| t == brightest).unwrap();
            prop_assert!(!flags[at]);
            // A larger share leaves at least the same lamps faint.
            let wider = faint(&terms, (share * 2.0).min(MAX_FAINT_SHARE));
            prop_assert!(flags.iter().zip(&wider).all(|(&a, &b)| !a || b));
        }
    }
}
