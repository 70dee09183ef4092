// The faint lamps of a point (`lightmesh/faint.rs`): those whose terms
// add up to at most the share directory.header.faint_parts /
// 2^FAINT_BUDGET_BITS of its lamps' light, whose penumbrae keep the
// half-ball's answer. Integer arithmetic on the bits of each lamp's term
// (Omega's largest channel), as the CPU's, so both skip the same lamps.
// Part of the coverage pass, whose `reach` and `lights` it reads.

struct FaintRule {
    // The largest exponent field of the point's lamps' terms.
    brightest: u32,
    // A lamp whose bucket is at least this is faint; FAINT_NONE: none is.
    first_faint: u32,
}

// A term's largest channel: what the rule weighs a lamp by.
fn faint_weight(term: vec3<f32>) -> u32 {
    return bitcast<u32>(lane_max(lane_max(term.x, term.y), term.z));
}

// The exponent field of a weight; 0 (no light, or subnormal) takes no part.
fn weight_exponent(weight: u32) -> u32 {
    return weight >> 23u & 0xffu;
}

fn weight_bucket(rule: FaintRule, weight: u32) -> u32 {
    return min(rule.brightest - weight_exponent(weight), FAINT_LAST_BUCKET);
}

fn saturating_add(a: u32, b: u32) -> u32 {
    let sum = a + b;
    return select(sum, 0xffffffffu, sum < a);
}

// Writes, after the point's reaching lights at `reach[base]`, the
// lamps among them that are not faint (`FaintLamps::faintest_kept`):
// those whose penumbrae formula (2) sizes, and for which the wide set is
// demanded.
fn mark_refined_lamps(point: ShadePoint, base: u32) {
    let light_words = directory.header.light_words;
    let parts = directory.header.faint_parts;
    var rule = FaintRule(0u, FAINT_NONE);
    var buckets: array<u32, FAINT_LAST_BUCKET + 1u>;
    // The brightest, the buckets, then the lamps kept: one loop, so Omega
    // is inlined once. Without a budget every lamp is kept, unweighed.
    for (var round = select(0u, 2u, parts == 0u); round < 3u; round++) {
        if round == 2u && parts != 0u {
            rule.first_faint = first_faint_bucket(buckets, parts);
        }
        for (var word = 0u; word < light_words; word++) {
            var lamps = reach[base + word] & lamp_bits(word);
            var refined = 0u;
            while lamps != 0u {
                let bit = firstTrailingBit(lamps);
                lamps &= lamps - 1u;
                if parts == 0u {
                    refined |= 1u << bit;
                    continue;
                }
                let weight = faint_weight(omega(point, lights[word * 32u + bit]));
                let exponent = weight_exponent(weight);
                if round == 0u {
                    rule.brightest = max(rule.brightest, exponent);
                } else if round == 1u && exponent != 0u {
                    let bucket = weight_bucket(rule, weight);
                    let significand = weight & 0x7fffffu | 0x800000u;
                    buckets[bucket] = saturating_add(buckets[bucket], significand);
                } else if round == 2u && !is_faint(rule, weight) {
                    refined |= 1u << bit;
                }
            }
            if round == 2u {
                reach[base + light_words + word] = refined;
            }
        }
    }
}

// The light rounded down, the last bucket left out; the faintest
// buckets' rounded up, skipped while within the budget.
fn first_faint_bucket(buckets: array<u32, FAINT_LAST_BUCKET + 1u>, parts: u32) -> u32 {
    var light = 0u;
    for (var bucket = 0u; bucket < FAINT_LAST_BUCKET; bucket++) {
        light = saturating_add(light, buckets[bucket] >> bucket);
    }
    let budget = (light >> FAINT_BUDGET_BITS) * parts;
    var skipped = 0u;
    var first_faint = FAINT_NONE;
    for (var bucket = FAINT_LAST_BUCKET; bucket >= 1u; bucket--) {
        let sum = buckets[bucket];
        let rounded_up = (sum >> bucket) + select(0u, 1u, (sum & ((1u << bucket) - 1u)) != 0u);
        skipped = saturating_add(skipped, rounded_up);
        if skipped > budget {
            break;
        }
        first_faint = bucket;
    }
    return first_faint;
}

// Whether a lamp of weight `weight` is faint under `rule`.
fn is_faint(rule: FaintRule, weight: u32) -> bool {
    return weight_exponent(weight) != 0u && weight_bucket(rule, weight) >= rule.first_faint;
}
