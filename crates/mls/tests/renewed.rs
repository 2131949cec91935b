//! A table built again for other controls (`Mls::renewed`, which keeps the bars'
//! integrals of the table before) gives the very same deformation as one built
//! afresh, to the bit.

use crate::support;

use glam::DVec2;
use mls::{Control, Mls, MlsOptions, deform_point};
use support::{Rng, VARIANTS, scene, vertices_around};

/// The deformation of `vertices` under `mls` for `posed`, as bit patterns.
fn bits(mls: &Mls, posed: &[Control], n: usize) -> Vec<[u64; 2]> {
    let mut out = vec![DVec2::ZERO; n];
    mls.deform(posed, &mut out).expect("a valid pose");
    out.iter().map(|p| [p.x.to_bits(), p.y.to_bits()]).collect()
}

#[test]
fn a_renewed_table_deforms_as_one_built_afresh() {
    let mut rng = Rng(41);
    for variant in VARIANTS {
        for alpha in [0.5, 1.0, 2.5] {
            let options = MlsOptions { alpha, variant };
            let (rest, posed) = scene(&mut rng, 4, 3, 150.0);
            let vertices = vertices_around(&mut rng, &rest, 300);
            let n = vertices.len();
            let fresh = Mls::new(&vertices, &rest, &options).expect("a valid scene");
            let want = bits(&fresh, &posed, n);
            // The controls before: one point handle fewer (an insertion), one bar
            // fewer (its integrals worked out now), every control (nothing changes),
            // the same controls under another α and on other vertices (nothing kept
            // applies).
            let point = rest.iter().position(|c| matches!(c, Control::Point(_)));
            let bar = rest.iter().position(|c| matches!(c, Control::Bar(_)));
            let without = |i: Option<usize>| -> Vec<Control> {
                let mut r = rest.clone();
                if let Some(i) = i {
                    r.remove(i);
                }
                r
            };
            let moved: Vec<DVec2> = vertices.iter().map(|v| *v + DVec2::new(0.5, 0.0)).collect();
            let before = [
                Mls::new(&vertices, &without(point), &options),
                Mls::new(&vertices, &without(bar), &options),
                Mls::new(&vertices, &rest, &options),
                Mls::new(
                    &vertices,
                    &rest,
                    &MlsOptions {
                        alpha: alpha + 1.0,
                        variant,
                    },
                ),
                Mls::new(&moved, &rest, &options),
            ];
            for (case, before) in before.into_iter().enumerate() {
                let renewed = (before.expect("a valid scene"))
                    .renewed(&vertices, &rest, &options)
                    .expect("a valid scene");
                assert!(
                    bits(&renewed, &posed, n) == want,
                    "{variant:?} α {alpha}, case {case}: renewed and fresh differ"
                );
            }
            // One point at a time, without a table (the table sums its terms in
            // another order).
            for (i, v) in vertices.iter().enumerate().step_by(7) {
                let p = deform_point(*v, &rest, &posed, &options).expect("valid");
                let [x, y] = want[i].map(f64::from_bits);
                assert!(
                    (p - DVec2::new(x, y)).length() <= 1e-9 * (1.0 + p.length()),
                    "{variant:?} α {alpha}: vertex {i} without a table: {p} vs ({x}, {y})"
                );
            }
        }
    }
}
