//! Symmetric 3×3 eigen decomposition (ours, cyclic Jacobi), enough for PCA of neighbourhoods.

use glam::{DMat3, DVec3};

/// Eigenvalues (ascending) and unit eigenvectors of the symmetric matrix `m`.
#[allow(clippy::needless_range_loop)] // index form mirrors the textbook rotation
pub(crate) fn sym_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m.to_cols_array_2d(); // a[col][row]; symmetric so the layout does not matter
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A' = Jᵀ A J with the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let vals = [a[0][0], a[1][1], a[2][2]];
    let vecs = [0, 1, 2].map(|k| DVec3::new(v[0][k], v[1][k], v[2][k]));
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| vals[i].total_cmp(&vals[j]));
    (
        idx.map(|i| vals[i]),
        idx.map(|i| vecs[i].normalize_or_zero()),
    )
}

/// Covariance (unnormalized) of `pts` about their centroid, and the centroid.
pub(crate) fn covariance(pts: impl Iterator<Item = DVec3> + Clone) -> (DMat3, DVec3) {
    let (mut c, mut n) = (DVec3::ZERO, 0.0f64);
    for p in pts.clone() {
        c += p;
        n += 1.0;
    }
    let c = c / n.max(1.0);
    let mut m = DMat3::ZERO;
    for p in pts {
        let d = p - c;
        m += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    (m, c)
}

/// RMS distance of `pts` to their best-fitting plane (the square root of the smallest
/// eigenvalue of their covariance over their number); 0 for fewer than three points.
pub fn plane_residual(pts: impl Iterator<Item = DVec3> + Clone) -> f64 {
    let n = pts.clone().count();
    if n < 3 {
        return 0.0;
    }
    let (m, _) = covariance(pts);
    sym_eigen(m * (1.0 / n as f64)).0[0].max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_of_a_rotated_diagonal_matrix() {
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let m = r * DMat3::from_diagonal(DVec3::new(3.0, 0.5, 1.0)) * r.transpose();
        let (vals, vecs) = sym_eigen(m);
        assert!((vals[0] - 0.5).abs() < 1e-12 && (vals[1] - 1.0).abs() < 1e-12);
        assert!((vals[2] - 3.0).abs() < 1e-12);
        for k in 0..3 {
            assert!((m * vecs[k] - vals[k] * vecs[k]).length() < 1e-12);
        }
        assert!((vecs[0].dot(r.y_axis)).abs() > 1.0 - 1e-12);
    }
}
