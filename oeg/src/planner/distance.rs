//! The exact Euclidean distance transform the inflation is measured with.

/// Stands for "no obstacle on this line" in the distance transform: far above any squared distance of a grid
/// the scenario limits allow, yet exact arithmetic keeps it finite.
const FAR: f64 = 1e30;

/// The squared Euclidean distance, in cells, from every cell of an `nx` x `ny` row-major grid to the nearest
/// `true` cell (Felzenszwalb and Huttenlocher's separable transform: columns, then rows).
pub(super) fn squared_distances(obstacle: &[bool], nx: usize, ny: usize) -> Vec<f64> {
    let mut d: Vec<f64> = obstacle.iter().map(|o| if *o { 0.0 } else { FAR }).collect();
    let n = nx.max(ny);
    let (mut f, mut out) = (vec![0.0; n], vec![0.0; n]);
    let (mut v, mut z) = (vec![0usize; n], vec![0.0; n + 1]);
    for x in 0..nx {
        for y in 0..ny {
            f[y] = d[y * nx + x];
        }
        lower_envelope(&f[..ny], &mut out[..ny], &mut v, &mut z);
        for y in 0..ny {
            d[y * nx + x] = out[y];
        }
    }
    for y in 0..ny {
        let row = &mut d[y * nx..(y + 1) * nx];
        f[..nx].copy_from_slice(row);
        lower_envelope(&f[..nx], &mut out[..nx], &mut v, &mut z);
        row.copy_from_slice(&out[..nx]);
    }
    d
}

/// One line of the transform: `out[q] = min_p (q - p)^2 + f[p]`, by the lower envelope of the parabolas.
fn lower_envelope(f: &[f64], out: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let meet = |f: &[f64], q: usize, p: usize| {
        let (qf, pf) = (q as f64, p as f64);
        ((f[q] + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf))
    };
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let mut s = meet(f, q, v[k]);
        while s <= z[k] {
            k -= 1;
            s = meet(f, q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let dq = q as f64 - v[k] as f64;
        *o = dq * dq + f[v[k]];
    }
}
