//! A from-scratch dense reference for both steps, written from the paper's
//! definitions and sharing no code with the crate: the energies are evaluated
//! directly (complex similarities, edge differences), their quadratic forms are read
//! off by probing, and the constrained minimum is found by Gaussian elimination.

use glam::DVec2;

use super::MeshData;

fn cmul(a: DVec2, b: DVec2) -> DVec2 {
    DVec2::new(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x)
}

fn cdiv(a: DVec2, b: DVec2) -> DVec2 {
    cmul(a, DVec2::new(b.x, -b.y)) / b.length_squared()
}

/// Step one's energy (eqs. 3–5): every corner of every triangle against where the
/// similarity taking the other two rest corners onto their deformed positions puts it.
pub fn step_one_energy(mesh: &MeshData, weights: &[f64], v: &[DVec2]) -> f64 {
    let r = &mesh.rest;
    let mut e = 0.0;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for c in 0..3 {
            let (i, j, k) = (
                tri[c] as usize,
                tri[(c + 1) % 3] as usize,
                tri[(c + 2) % 3] as usize,
            );
            let z = cdiv(v[k] - v[j], r[k] - r[j]);
            let desired = v[j] + cmul(z, r[i] - r[j]);
            e += weights[t] * (v[i] - desired).length_squared();
        }
    }
    e
}

/// Step two's energy (eq. 12): every triangle's three edges against the rest edges
/// turned by that triangle's rotation.
pub fn step_two_energy(mesh: &MeshData, weights: &[f64], rotations: &[DVec2], v: &[DVec2]) -> f64 {
    let r = &mesh.rest;
    let mut e = 0.0;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for c in 0..3 {
            let (i, j) = (tri[c] as usize, tri[(c + 1) % 3] as usize);
            let target = cmul(rotations[t], r[j] - r[i]);
            e += weights[t] * ((v[j] - v[i]) - target).length_squared();
        }
    }
    e
}

/// The rotation of the similarity fitting a rest triangle onto `q` in the least-squares
/// sense (centroid Procrustes), scale removed.
pub fn fitted_rotation(rest: [DVec2; 3], q: [DVec2; 3]) -> DVec2 {
    let rc = (rest[0] + rest[1] + rest[2]) / 3.0;
    let qc = (q[0] + q[1] + q[2]) / 3.0;
    let mut z = DVec2::ZERO;
    for k in 0..3 {
        let a = rest[k] - rc;
        z += cmul(DVec2::new(a.x, -a.y), q[k] - qc);
    }
    z.normalize()
}

/// Minimises a quadratic `energy` of all vertex positions with `constrained[i]` held
/// at `targets[i]`: probes the Hessian and gradient at zero, then solves the free
/// block densely.
pub fn minimise(
    n: usize,
    constrained: &[u32],
    targets: &[DVec2],
    energy: impl Fn(&[DVec2]) -> f64,
) -> Vec<DVec2> {
    let dim = 2 * n;
    let at = |x: &[f64]| {
        let v: Vec<DVec2> = (0..n).map(|i| DVec2::new(x[2 * i], x[2 * i + 1])).collect();
        energy(&v)
    };
    let mut x = vec![0.0; dim];
    let e0 = at(&x);
    let mut e1 = vec![0.0; dim];
    for a in 0..dim {
        x[a] = 1.0;
        e1[a] = at(&x);
        x[a] = 0.0;
    }
    // Hessian (2G) and gradient at 0.
    let mut hess = vec![vec![0.0; dim]; dim];
    for a in 0..dim {
        for b in a..dim {
            x[a] += 1.0;
            x[b] += 1.0;
            let eab = at(&x);
            x[a] = 0.0;
            x[b] = 0.0;
            // Twice the quadratic form's entry, on and off the diagonal alike.
            let h = eab - e1[a] - e1[b] + e0;
            hess[a][b] = h;
            hess[b][a] = h;
        }
    }
    let grad: Vec<f64> = (0..dim).map(|a| e1[a] - e0 - hess[a][a] / 2.0).collect();
    let mut fixed = vec![None; dim];
    for (&v, &t) in constrained.iter().zip(targets) {
        fixed[2 * v as usize] = Some(t.x);
        fixed[2 * v as usize + 1] = Some(t.y);
    }
    let free: Vec<usize> = (0..dim).filter(|&a| fixed[a].is_none()).collect();
    let mut a_mat: Vec<Vec<f64>> = free
        .iter()
        .map(|&r| free.iter().map(|&c| hess[r][c]).collect())
        .collect();
    let mut rhs: Vec<f64> = free
        .iter()
        .map(|&r| {
            -grad[r]
                - (0..dim)
                    .filter_map(|c| fixed[c].map(|q| hess[r][c] * q))
                    .sum::<f64>()
        })
        .collect();
    let u = gauss(&mut a_mat, &mut rhs);
    let mut out = vec![0.0; dim];
    for a in 0..dim {
        if let Some(q) = fixed[a] {
            out[a] = q;
        }
    }
    for (k, &a) in free.iter().enumerate() {
        out[a] = u[k];
    }
    (0..n)
        .map(|i| DVec2::new(out[2 * i], out[2 * i + 1]))
        .collect()
}

/// Solves `a·x = b` by Gaussian elimination with partial pivoting.
fn gauss(a: &mut [Vec<f64>], b: &mut [f64]) -> Vec<f64> {
    let n = b.len();
    for col in 0..n {
        let p = (col..n)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .expect("non-empty");
        a.swap(col, p);
        b.swap(col, p);
        let d = a[col][col];
        assert!(d.abs() > 1e-12, "singular reference system");
        let pivot_row = a[col].clone();
        for r in col + 1..n {
            let f = a[r][col] / d;
            if f != 0.0 {
                for (x, p) in a[r][col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= f * p;
                }
                b[r] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Both steps from scratch: step one's minimiser, then the fitted rotations, then
/// step two's minimiser. Returns `(step_one, final)`.
pub fn two_steps(
    mesh: &MeshData,
    weights: &[f64],
    constrained: &[u32],
    targets: &[DVec2],
) -> (Vec<DVec2>, Vec<DVec2>) {
    let n = mesh.rest.len();
    let one = minimise(n, constrained, targets, |v| {
        step_one_energy(mesh, weights, v)
    });
    let rotations: Vec<DVec2> = mesh
        .triangles
        .iter()
        .map(|t| fitted_rotation(t.map(|v| mesh.rest[v as usize]), t.map(|v| one[v as usize])))
        .collect();
    let two = minimise(n, constrained, targets, |v| {
        step_two_energy(mesh, weights, &rotations, v)
    });
    (one, two)
}
