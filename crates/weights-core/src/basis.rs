//! The C² basis function φ of the paper: the y-part of a degree-n Bézier curve whose
//! x-controls are i/n (so x(t) = t) and whose y-controls are 1, 1, 1, …, 0, 0, 0.

/// How the y-controls between the three leading ones and the three trailing zeros are
/// placed (only degrees n > 5 have such middle controls).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MiddleControls {
    /// Every middle control is 0.5.
    #[default]
    Half,
    /// The middle controls lie on the line from b₂ = (2/n, 1) to b_{n−2} = ((n−2)/n, 0).
    Linear,
}

/// The smallest degree that gives a C² basis (φ′ and φ″ vanish at both ends).
pub const MIN_DEGREE: u32 = 5;
/// The largest degree accepted; higher degrees only sharpen the fall-off further.
pub const MAX_DEGREE: u32 = 25;

/// The radial basis φ: [0, ∞) → [0, 1] with φ(0) = 1, φ(t) = 0 for t ≥ 1, and
/// φ′ = φ″ = 0 at t = 0 and t = 1.
///
/// ```
/// use weights_core::Basis;
/// let phi = Basis::default(); // degree 5: 1 − 10t³ + 15t⁴ − 6t⁵
/// assert_eq!(phi.eval(0.0), 1.0);
/// assert_eq!(phi.eval(1.0), 0.0);
/// assert!((phi.eval(0.5) - 0.5).abs() < 1e-15);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Basis {
    degree: u32,
    middle: MiddleControls,
    /// Power-basis coefficients c₀ … c_n of the polynomial on [0, 1].
    coefficients: Vec<f64>,
}

impl Default for Basis {
    fn default() -> Self {
        Self::new(MIN_DEGREE, MiddleControls::Half).expect("degree 5 is valid")
    }
}

impl Basis {
    /// The basis of the given degree; `None` unless `MIN_DEGREE ≤ degree ≤ MAX_DEGREE`.
    pub fn new(degree: u32, middle: MiddleControls) -> Option<Self> {
        if !(MIN_DEGREE..=MAX_DEGREE).contains(&degree) {
            return None;
        }
        let n = degree as usize;
        let controls: Vec<f64> = (0..=n)
            .map(|i| match i {
                _ if i <= 2 => 1.0,
                _ if i >= n - 2 => 0.0,
                _ => match middle {
                    MiddleControls::Half => 0.5,
                    MiddleControls::Linear => 1.0 - (i - 2) as f64 / (n - 4) as f64,
                },
            })
            .collect();
        // Bernstein to power basis: c_k = Σ_{i≤k} y_i · C(n,k) · C(k,i) · (−1)^{k−i}.
        let coefficients = (0..=n)
            .map(|k| {
                (0..=k)
                    .map(|i| {
                        let sign = if (k - i) % 2 == 0 { 1.0 } else { -1.0 };
                        controls[i] * binomial(n, k) * binomial(k, i) * sign
                    })
                    .sum()
            })
            .collect();
        Some(Self {
            degree,
            middle,
            coefficients,
        })
    }

    /// The polynomial degree n.
    pub fn degree(&self) -> u32 {
        self.degree
    }

    /// How the middle controls are placed.
    pub fn middle(&self) -> MiddleControls {
        self.middle
    }

    /// φ(t): 1 at t ≤ 0, 0 at t ≥ 1 (and for NaN), the polynomial in between.
    #[inline]
    pub fn eval(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 1.0;
        }
        if t.is_nan() || t >= 1.0 {
            return 0.0;
        }
        let value = self
            .coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, &c| acc * t + c);
        value.clamp(0.0, 1.0)
    }

    /// φ′(t) on [0, 1] (0 outside).
    pub fn derivative(&self, t: f64) -> f64 {
        if !(0.0..=1.0).contains(&t) {
            return 0.0;
        }
        self.coefficients
            .iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (k, &c)| acc * t + k as f64 * c)
    }

    /// φ″(t) on [0, 1] (0 outside).
    pub fn second_derivative(&self, t: f64) -> f64 {
        if !(0.0..=1.0).contains(&t) {
            return 0.0;
        }
        self.coefficients
            .iter()
            .enumerate()
            .skip(2)
            .rev()
            .fold(0.0, |acc, (k, &c)| acc * t + (k * (k - 1)) as f64 * c)
    }
}

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn all_bases() -> Vec<Basis> {
        (MIN_DEGREE..=12)
            .flat_map(|n| {
                [MiddleControls::Half, MiddleControls::Linear]
                    .into_iter()
                    .filter_map(move |m| Basis::new(n, m))
            })
            .collect()
    }

    #[test]
    fn degree_five_is_the_quintic_smoothstep() {
        let phi = Basis::default();
        for i in 0..=100 {
            let t = i as f64 / 100.0;
            let expected = 1.0 - 10.0 * t.powi(3) + 15.0 * t.powi(4) - 6.0 * t.powi(5);
            assert!((phi.eval(t) - expected).abs() < 1e-14, "t = {t}");
        }
    }

    #[test]
    fn end_conditions_hold_for_every_degree() {
        for phi in all_bases() {
            let name = format!("n = {}, {:?}", phi.degree(), phi.middle());
            assert_eq!(phi.eval(0.0), 1.0, "{name}");
            assert_eq!(phi.eval(1.0), 0.0, "{name}");
            assert!(phi.derivative(0.0).abs() < 1e-9, "{name}");
            assert!(phi.derivative(1.0).abs() < 1e-9, "{name}");
            assert!(phi.second_derivative(0.0).abs() < 1e-9, "{name}");
            assert!(phi.second_derivative(1.0).abs() < 1e-9, "{name}");
            // The polynomial itself reaches 0 at t = 1 (continuity with φ = 0 beyond).
            let at_one: f64 = phi.coefficients.iter().sum();
            assert!(at_one.abs() < 1e-9, "{name}");
        }
    }

    #[test]
    fn invalid_degrees_are_refused() {
        assert!(Basis::new(4, MiddleControls::Half).is_none());
        assert!(Basis::new(MAX_DEGREE + 1, MiddleControls::Linear).is_none());
    }

    proptest! {
        #[test]
        fn strictly_decreasing_inside(t in 1e-6f64..(1.0 - 1e-6)) {
            for phi in all_bases() {
                prop_assert!(phi.derivative(t) < 0.0, "n = {}, t = {t}", phi.degree());
                let v = phi.eval(t);
                prop_assert!(v > 0.0 && v < 1.0);
            }
        }
    }
}
