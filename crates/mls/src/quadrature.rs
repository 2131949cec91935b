//! Gauss–Legendre quadrature: nodes and weights on [−1, 1], computed once by Newton's
//! method on the Legendre polynomial (to the last bit or so of an `f64`).

use std::sync::LazyLock;

/// Number of nodes of the rule the bar integrals use on every sub-interval.
pub(crate) const NODES: usize = 16;

/// The `NODES`-point rule as `(node, weight)` pairs on [−1, 1].
pub(crate) static RULE: LazyLock<[(f64, f64); NODES]> = LazyLock::new(|| {
    let mut rule = [(0.0, 0.0); NODES];
    for (slot, pair) in rule.iter_mut().zip(gauss_legendre(NODES)) {
        *slot = pair;
    }
    rule
});

/// The `n`-point Gauss–Legendre rule on [−1, 1], nodes ascending.
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess for the i-th largest root, then Newton.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            derivative = dp;
            let step = p / dp;
            x -= step;
            if step.abs() <= 1e-17 {
                break;
            }
        }
        let (_, dp) = legendre(n, x);
        if dp.is_finite() {
            derivative = dp;
        }
        let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
        rule.push((x, weight));
    }
    rule.reverse();
    rule
}

/// `P_n(x)` and `P_n'(x)` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let n = n as f64;
    (p1, n * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        for n in [4, 8, 16, 32] {
            let rule = gauss_legendre(n);
            for degree in 0..(2 * n) {
                let got: f64 = rule.iter().map(|(x, w)| w * x.powi(degree as i32)).sum();
                let want = if degree % 2 == 0 {
                    2.0 / (degree as f64 + 1.0)
                } else {
                    0.0
                };
                assert!(
                    (got - want).abs() < 1e-14,
                    "n {n} degree {degree}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn static_rule_matches() {
        let rule = gauss_legendre(NODES);
        assert_eq!(RULE.len(), rule.len());
        let total: f64 = RULE.iter().map(|(_, w)| w).sum();
        assert!((total - 2.0).abs() < 1e-15);
        assert!(RULE.windows(2).all(|w| w[0].0 < w[1].0));
    }
}
