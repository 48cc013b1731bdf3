//! The Δt → 0 limit of a bias ladder and how much it depends on the fit: weighted
//! least squares of `y = a + C₁ Δt (+ C₂ Δt²)` (weights 1/SE²) over several ranges of
//! the finest steps. The spread of `a` over these reasonable fits is the fit-model
//! uncertainty, which the statistical SE of one fit leaves out.

/// One fit of the ladder.
#[derive(Clone, Copy, Debug)]
pub struct Fit {
    /// Polynomial degree in Δt (1 or 2).
    pub degree: usize,
    /// Largest Δt in the fit.
    pub max_dt: f64,
    /// Points used.
    pub points: usize,
    /// The intercept (the limit) and its standard error.
    pub limit: f64,
    pub se: f64,
    /// χ² of the residuals and its degrees of freedom (points − degree − 1).
    pub chi2: f64,
    pub dof: usize,
}

/// Weighted least squares of a polynomial of `degree` through `(x, y ± se)`:
/// `(coefficients, covariance of the intercept, χ²)`; `None` when there are fewer
/// points than coefficients or the normal equations are singular.
fn polyfit(x: &[f64], y: &[f64], se: &[f64], degree: usize) -> Option<(Vec<f64>, f64, f64)> {
    let p = degree + 1;
    if x.len() < p {
        return None;
    }
    // normal equations A c = b, A = Xᵀ W X, solved with their inverse by Gauss–Jordan
    let mut a = vec![vec![0.0; 2 * p]; p];
    let mut b = vec![0.0; p];
    for k in 0..x.len() {
        let w = 1.0 / (se[k] * se[k]);
        for (i, (row, bi)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
            *bi += w * x[k].powi(i as i32) * y[k];
            for (j, v) in row.iter_mut().take(p).enumerate() {
                *v += w * x[k].powi((i + j) as i32);
            }
        }
    }
    for (i, row) in a.iter_mut().enumerate() {
        row[p + i] = 1.0;
    }
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, piv);
        let d = a[c][c];
        for v in a[c].iter_mut() {
            *v /= d;
        }
        for r in 0..p {
            if r != c {
                let f = a[r][c];
                let pivot_row = a[c].clone();
                for (v, pv) in a[r].iter_mut().zip(pivot_row) {
                    *v -= f * pv;
                }
            }
        }
    }
    let coef: Vec<f64> = (0..p)
        .map(|i| (0..p).map(|j| a[i][p + j] * b[j]).sum())
        .collect();
    let chi2 = (0..x.len())
        .map(|k| {
            let fit: f64 = (0..p).map(|i| coef[i] * x[k].powi(i as i32)).sum();
            ((y[k] - fit) / se[k]).powi(2)
        })
        .sum();
    Some((coef, a[0][p], chi2))
}

/// The fits of a ladder `(Δt, y, se)` (any order): quadratic over Δt ≤ `max_dt` and
/// the next range down, linear over the three and the two finest steps (the widest
/// first; [`central`] picks the reported one).
pub fn fits(h: &[f64], y: &[f64], se: &[f64], max_dt: f64) -> Vec<Fit> {
    let mut idx: Vec<usize> = (0..h.len()).collect();
    idx.sort_by(|&i, &j| h[i].total_cmp(&h[j]));
    let (h, y, se): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        idx.iter().map(|&i| h[i]).collect(),
        idx.iter().map(|&i| y[i]).collect(),
        idx.iter().map(|&i| se[i]).collect(),
    );
    let upto = |m: f64| h.iter().filter(|&&d| d <= m * (1.0 + 1e-12)).count();
    let n = upto(max_dt);
    let plans = [
        (2, n),
        (2, n.saturating_sub(1)),
        (1, 3.min(n)),
        (1, 2.min(n)),
    ];
    plans
        .iter()
        .filter_map(|&(degree, k)| {
            let (c, var, chi2) = polyfit(&h[..k], &y[..k], &se[..k], degree)?;
            Some(Fit {
                degree,
                max_dt: h[k - 1],
                points: k,
                limit: c[0],
                se: var.sqrt(),
                chi2,
                dof: k - degree - 1,
            })
        })
        .collect()
}

/// The reported fit: the first (widest) whose χ² is consistent with its degrees of
/// freedom (χ² ≤ dof + 3 √(2 dof)), else the first.
pub fn central(fits: &[Fit]) -> Option<&Fit> {
    fits.iter()
        .find(|f| f.dof > 0 && f.chi2 <= f.dof as f64 + 3.0 * (2.0 * f.dof as f64).sqrt())
        .or(fits.first())
}

/// `(min, max)` of the fits' limits.
pub fn spread(fits: &[Fit]) -> (f64, f64) {
    fits.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), f| {
            (lo.min(f.limit), hi.max(f.limit))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line through exact points is recovered by every fit, with χ² = 0; a
    /// quadratic one only by the quadratic fits.
    #[test]
    fn fits_recover_polynomials() {
        let h = [0.2, 0.1, 0.05, 0.025, 0.0125];
        let se = [0.01; 5];
        let line: Vec<f64> = h.iter().map(|d| 37.0 - 20.0 * d).collect();
        for f in fits(&h, &line, &se, 0.2) {
            assert!((f.limit - 37.0).abs() < 1e-9, "{f:?}");
            assert!(f.chi2 < 1e-12);
        }
        let quad: Vec<f64> = h.iter().map(|d| 37.0 - 20.0 * d + 50.0 * d * d).collect();
        let fs = fits(&h, &quad, &se, 0.2);
        assert_eq!(fs.len(), 4);
        assert!((fs[0].limit - 37.0).abs() < 1e-9 && (fs[1].limit - 37.0).abs() < 1e-9);
        assert_eq!((fs[0].points, fs[0].dof), (5, 2));
        // the two-point line is Richardson's 2 y(h/2) − y(h): 37 − 50 h²/2 off at h = 1/40
        let rr = 2.0 * quad[4] - quad[3];
        assert!((fs[3].limit - rr).abs() < 1e-9);
        assert!(fs[3].limit < 37.0 && fs[2].chi2 > 1.0);
        // the SE of a two-point line: Richardson's √(4 se² + se²)
        assert!((fs[3].se - (5.0f64).sqrt() * 0.01).abs() < 1e-12);
    }

    /// The published specular ladder (docs/results/maftei2016-reproduction.md): the
    /// quadratic fit over Δt ≤ 0.2 gives 37.1314 ± 0.0064 and a poor χ²; the fits'
    /// limits differ by far more than that SE.
    #[test]
    fn the_published_specular_ladder() {
        let h = [0.2, 0.1, 0.05, 0.025, 0.0125];
        let y = [33.5031, 34.5490, 35.6738, 36.3461, 36.7193];
        let se = [0.0059, 0.0060, 0.0061, 0.0061, 0.0062];
        let fs = fits(&h, &y, &se, 0.2);
        assert!((fs[0].limit - 37.1314).abs() < 2e-4, "{:?}", fs[0]);
        assert!((fs[0].se - 0.0064).abs() < 2e-4, "{:?}", fs[0]);
        let (lo, hi) = spread(&fs);
        assert!(hi - lo > 5.0 * fs[0].se, "{lo} .. {hi}");
        // χ² = 13 on 2 degrees of freedom: the reported fit is the 4-step quadratic
        let c = central(&fs).unwrap();
        assert!((c.limit - 37.1043).abs() < 2e-4 && c.points == 4, "{c:?}");
    }
}
