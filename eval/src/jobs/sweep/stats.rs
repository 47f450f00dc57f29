//! Means with 95 % confidence intervals: Student's t interval for a mean over replicates, Wilson's score
//! interval for a rate (a fraction of runs or obstacles).

/// A summary of a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Summary {
    /// Sample size.
    pub n: usize,
    /// Mean (or rate).
    pub mean: f64,
    /// Sample standard deviation (n - 1 in the denominator); NaN below two values.
    pub std: f64,
    /// Lower end of the 95 % interval; NaN when there is none.
    pub low: f64,
    /// Upper end.
    pub high: f64,
}

impl Summary {
    /// A sample of `n` with a mean (NaN: none) and no spread or interval.
    fn without_interval(n: usize, mean: f64) -> Self {
        Self {
            n,
            mean,
            std: f64::NAN,
            low: f64::NAN,
            high: f64::NAN,
        }
    }
}

/// The 97.5 % quantile of Student's t with `df` degrees of freedom: the half-width factor of a two-sided
/// 95 % interval. Exact table values to 6 digits up to 30 degrees of freedom, the Cornish-Fisher expansion
/// beyond (error below 1e-5 there).
pub(crate) fn t_975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706205, 4.302653, 3.182446, 2.776445, 2.570582, 2.446912, 2.364624, 2.306004, 2.262157, 2.228139,
        2.200985, 2.178813, 2.160369, 2.144787, 2.131450, 2.119905, 2.109816, 2.100922, 2.093024, 2.085963,
        2.079614, 2.073873, 2.068658, 2.063899, 2.059539, 2.055529, 2.051831, 2.048407, 2.045230, 2.042272,
    ];
    if df == 0 {
        return f64::NAN;
    }
    if df <= 30 {
        return TABLE[df - 1];
    }
    let z: f64 = 1.959_963_984_540_054;
    let v = df as f64;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * v)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v * v * v)
}

/// Mean and Student's t 95 % interval of the finite values of `xs` (non-finite ones are left out).
pub(crate) fn mean_interval(xs: &[f64]) -> Summary {
    let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Summary::without_interval(0, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return Summary::without_interval(n, mean);
    }
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let std = var.sqrt();
    let half = t_975(n - 1) * std / (n as f64).sqrt();
    Summary {
        n,
        mean,
        std,
        low: mean - half,
        high: mean + half,
    }
}

/// A rate `k / n` with Wilson's 95 % score interval (sensible at 0 and 1, unlike the normal interval).
pub(crate) fn rate_interval(k: usize, n: usize) -> Summary {
    if n == 0 {
        return Summary::without_interval(0, f64::NAN);
    }
    let z: f64 = 1.959_963_984_540_054;
    let (nf, p) = (n as f64, k as f64 / n as f64);
    let denom = 1.0 + z * z / nf;
    let centre = (p + z * z / (2.0 * nf)) / denom;
    let half = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / denom;
    Summary {
        n,
        mean: p,
        std: (p * (1.0 - p)).sqrt(),
        low: (centre - half).max(0.0),
        high: (centre + half).min(1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_tables() {
        // R: qt(0.975, df)
        for (df, q) in [
            (1, 12.706205),
            (9, 2.262157),
            (30, 2.042272),
            (40, 2.021075),
            (100, 1.983972),
            (1000, 1.962339),
        ] {
            assert!((t_975(df) - q).abs() < 2e-5, "df {df}: {} vs {q}", t_975(df));
        }
    }

    #[test]
    fn the_mean_interval_has_the_known_answer() {
        // 1..5: mean 3, s = sqrt(2.5), half-width t(4) s / sqrt(5) = 2.776445 * 0.707107 = 1.963243.
        let s = mean_interval(&[1.0, 2.0, 3.0, 4.0, 5.0, f64::NAN]);
        assert_eq!(s.n, 5);
        assert!((s.mean - 3.0).abs() < 1e-12);
        assert!((s.std - 2.5f64.sqrt()).abs() < 1e-12);
        assert!(
            (s.low - 1.036757).abs() < 1e-5 && (s.high - 4.963243).abs() < 1e-5,
            "{s:?}"
        );
        assert!(mean_interval(&[2.0]).low.is_nan());
    }

    #[test]
    fn the_wilson_interval_has_the_known_answer() {
        // 8 of 10: Wilson 95 % is [0.4902, 0.9433] (Newcombe 1998, Table I style check).
        let s = rate_interval(8, 10);
        assert!(
            (s.low - 0.490_162).abs() < 1e-4 && (s.high - 0.943_317).abs() < 1e-4,
            "{s:?}"
        );
        let zero = rate_interval(0, 10);
        assert!(
            zero.low == 0.0 && (zero.high - 0.277_533).abs() < 1e-4,
            "{zero:?}"
        );
    }
}
