//! Stratified allocation: split `n` items among categories with exact quotas (largest remainder, ties broken
//! by category order), then spread them in a seeded random order. Planned proportions equal the targets up to
//! one unit of rounding, however small the stratum.

use rand::seq::SliceRandom;
use rand::{Rng, RngExt};

/// Counts per category: `floor(n × share)` plus one for the largest remainders until they sum to `n`.
/// Shares need not be normalised; categories with share 0 get 0. Returns all zeros when every share is 0.
pub fn largest_remainder(n: usize, shares: &[f64]) -> Vec<usize> {
    let total: f64 = shares.iter().filter(|s| s.is_finite() && **s > 0.0).sum();
    if total <= 0.0 || n == 0 {
        return vec![0; shares.len()];
    }
    let exact: Vec<f64> = shares
        .iter()
        .map(|s| {
            if s.is_finite() && *s > 0.0 {
                s / total * n as f64
            } else {
                0.0
            }
        })
        .collect();
    let mut counts: Vec<usize> = exact.iter().map(|x| x.floor() as usize).collect();
    let assigned: usize = counts.iter().sum();
    let mut order: Vec<usize> = (0..shares.len()).filter(|&i| exact[i] > 0.0).collect();
    // Largest remainder first; ties go to the earlier category, so the result is deterministic.
    order.sort_by(|&a, &b| {
        (exact[b] - exact[b].floor())
            .total_cmp(&(exact[a] - exact[a].floor()))
            .then(a.cmp(&b))
    });
    for &i in order.iter().cycle().take(n.saturating_sub(assigned)) {
        counts[i] += 1;
    }
    counts
}

/// `n` category indices with exact quotas, in a random order drawn from `rng`.
pub fn allocate(n: usize, shares: &[f64], rng: &mut impl Rng) -> Vec<usize> {
    let counts = largest_remainder(n, shares);
    let mut out: Vec<usize> = counts
        .iter()
        .enumerate()
        .flat_map(|(i, &c)| std::iter::repeat_n(i, c))
        .collect();
    out.shuffle(rng);
    out
}

/// Chooses `k` of `weights.len()` items without replacement, each with probability proportional to its
/// weight (Efraimidis–Spirakis keys). Items of weight 0 are chosen only when nothing else is left.
/// Returns a membership mask.
pub fn weighted_choice(k: usize, weights: &[f64], rng: &mut impl Rng) -> Vec<bool> {
    let mut keyed: Vec<(f64, usize)> = weights
        .iter()
        .enumerate()
        .map(|(i, &w)| {
            let u: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
            let key = if w > 0.0 { u.ln() / w } else { f64::NEG_INFINITY };
            (key, i)
        })
        .collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut mask = vec![false; weights.len()];
    for &(_, i) in keyed.iter().take(k) {
        mask[i] = true;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn quotas_sum_to_n_and_stay_within_one_unit() {
        for n in 0..200 {
            let shares = [0.30, 0.25, 0.10, 0.20, 0.15];
            let counts = largest_remainder(n, &shares);
            assert_eq!(counts.iter().sum::<usize>(), n);
            for (c, s) in counts.iter().zip(shares) {
                assert!((*c as f64 - s * n as f64).abs() < 1.0, "n={n} {counts:?}");
            }
        }
        assert_eq!(largest_remainder(3, &[0.5, 0.5]), vec![2, 1]);
        assert_eq!(largest_remainder(5, &[0.0, 0.0]), vec![0, 0]);
        assert_eq!(largest_remainder(4, &[1.0, 0.0, 1.0]), vec![2, 0, 2]);
    }

    #[test]
    fn weighted_choice_picks_exactly_k_and_prefers_heavy_items() {
        let mut rng = rand_chacha::ChaCha20Rng::seed_from_u64(1);
        let mut heavy = 0;
        for _ in 0..2000 {
            let mask = weighted_choice(1, &[0.9, 0.1], &mut rng);
            assert_eq!(mask.iter().filter(|m| **m).count(), 1);
            heavy += usize::from(mask[0]);
        }
        assert!((1700..1900).contains(&heavy), "{heavy}");
        assert_eq!(
            weighted_choice(2, &[0.0, 1.0, 0.0], &mut rng)
                .iter()
                .filter(|m| **m)
                .count(),
            2
        );
    }
}
