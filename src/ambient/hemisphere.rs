//! Statistics of a new value's hemisphere cells: the outlier limit, the variance estimate
//! and Neyman shares of super-sampling, and the gradients (Ward & Heckbert 1992).

use crate::color::Color;
use glam::DVec3;
use std::f64::consts::PI;

/// The outlier limit for a value of `samples` sample rays: `f` up to 128 samples, then
/// growing as the square root of the count. A value of many samples catches a small bright
/// source (a caustic, a highlight) often enough that cutting it removes real light: on the
/// spheres scene the fixed limit left the floor's indirect light 20–40% low (docs/ambient.md).
pub fn outlier_limit(f: f64, samples: u64) -> f64 {
    f * (samples as f64 / 128.0).max(1.0).sqrt()
}

/// Limits every cell's brightness to `f` × the sum of all the other cells' brightness
/// (scaling its colour), so that one sample that caught a rare bright path (a highlight seen
/// from below a glossy object, a caustic) cannot make the whole value: with few cells such a
/// spike would otherwise be spread over the value's radii. `b` holds the cells' brightness
/// and is scaled with them. Hemispheres of fewer than 16 cells are left alone.
pub fn clamp_outliers(cells: &mut [Color], b: &mut [f64], f: f64) {
    if cells.len() < 16 {
        return;
    }
    let total: f64 = b.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return;
    }
    for (c, bi) in cells.iter_mut().zip(b.iter_mut()) {
        let cap = f * (total - *bi);
        if *bi > cap && *bi > 0.0 {
            let k = cap.max(0.0) / *bi;
            *c *= k;
            *bi *= k;
        }
    }
}

/// One hemisphere cell: the running sum of its samples.
#[derive(Clone, Copy, Default)]
pub(super) struct Cell {
    sum: Color,
    pub(super) count: u32,
    rinv: f64,
    /// First sample's hit point relative to the shading point (the mesh vertex).
    pub(super) hit: DVec3,
}

impl Cell {
    pub(super) fn add(&mut self, c: Color, t: f64) {
        self.sum += c;
        self.count += 1;
        self.rinv += 1.0 / t;
    }
    pub(super) fn mean(&self) -> Color {
        if self.count == 0 {
            Color::ZERO
        } else {
            self.sum / self.count as f64
        }
    }
    /// Harmonic mean distance of the cell's samples.
    pub(super) fn dist(&self, max: f64) -> f64 {
        if self.count == 0 {
            max
        } else {
            self.count as f64 / self.rinv
        }
    }
}

/// The columns k − 1, k and k + 1 of a ring of `nphi` cells, wrapping in φ.
#[inline]
fn phi_neighbours(k: usize, nphi: usize) -> [usize; 3] {
    [(k + nphi - 1) % nphi, k, (k + 1) % nphi]
}

/// Per-cell variance estimate for super-sampling: the mean squared brightness difference with
/// the (up to 8) neighbouring cells, wrapping in φ, not across the pole or the horizon.
pub fn cell_variances(b: &[f64], m: usize, nphi: usize) -> Vec<f64> {
    let mut out = vec![0.0; m * nphi];
    for j in 0..m {
        for k in 0..nphi {
            let c = b[j * nphi + k];
            let (mut s, mut cnt) = (0.0, 0usize);
            for_neighbours((j, k), (m, nphi), false, |i| {
                let d = b[i] - c;
                s += d * d;
                cnt += 1;
            });
            out[j * nphi + k] = if cnt > 0 { s / cnt as f64 } else { 0.0 };
        }
    }
    out
}

/// Calls `f` with the index of each of the up to 8 neighbours of cell (j, k): the rings
/// j − 1 to j + 1 that exist (not across the pole or the horizon), the columns k − 1 to
/// k + 1 wrapping in φ, the cell itself left out. With `distinct`, a column met twice in a
/// ring of fewer than 3 columns (or the cell's own column met again) is visited once.
fn for_neighbours(
    (j, k): (usize, usize),
    (m, nphi): (usize, usize),
    distinct: bool,
    mut f: impl FnMut(usize),
) {
    let cols = phi_neighbours(k, nphi);
    for dj in -1i64..=1 {
        let jj = j as i64 + dj;
        if jj < 0 || jj >= m as i64 {
            continue;
        }
        let row = jj as usize * nphi;
        for (ci, &kk) in cols.iter().enumerate() {
            if dj == 0 && ci == 1 {
                continue;
            }
            if distinct && ((ci != 1 && kk == k) || (ci == 2 && kk == cols[0])) {
                continue;
            }
            f(row + kk);
        }
    }
}

/// How super-sampling shares its extra rays among the cells (not normalised): the estimated
/// standard deviation of each cell, so that a cell's extra rays are proportional to it — the
/// allocation that minimises the variance of a stratified mean for a given number of samples
/// (Neyman). The variance estimate of [`cell_variances`] is first blurred (half the cell's own,
/// half the mean of its 3×3 neighbourhood, wrapping in φ, clamped at the pole and horizon), so a
/// small bright patch (a sunlit spot) that one cell's sample found also draws rays into the
/// cells around it, which may hold the rest of the patch unseen by their first sample.
pub fn super_sample_shares(b: &[f64], m: usize, nphi: usize) -> Vec<f64> {
    let var = cell_variances(b, m, nphi);
    let mut out = vec![0.0; m * nphi];
    for j in 0..m {
        for k in 0..nphi {
            let mut s = 0.0;
            let cols = phi_neighbours(k, nphi);
            for dj in -1i64..=1 {
                let row = (j as i64 + dj).clamp(0, m as i64 - 1) as usize * nphi;
                for &kk in &cols {
                    s += var[row + kk];
                }
            }
            out[j * nphi + k] = (0.5 * var[j * nphi + k] + 0.5 * s / 9.0).sqrt();
        }
    }
    out
}

/// [`super_sample_shares`] without a cell's own first sample: each cell's share is the
/// spread (standard deviation) of the first samples of its up to 8 neighbours (wrapping in
/// φ, not across the pole or the horizon), never of its own. A cell's extra rays then do
/// not depend on its own first sample, so the mean of its samples stays an unbiased
/// estimate of its light: where the share grows with the cell's own sample (a bright first
/// sample draws rays that dilute it, a dark one keeps its full weight), a value is biased
/// low by about 1/`-ad` (docs/ambient.md, "Super-sampling's own bias"). A bright patch that one cell's
/// sample found still draws rays into the cells around it, whose neighbourhood holds it.
pub fn super_sample_shares_unbiased(b: &[f64], m: usize, nphi: usize) -> Vec<f64> {
    let mut out = vec![0.0; m * nphi];
    for j in 0..m {
        for k in 0..nphi {
            let (mut vals, mut n) = ([0.0f64; 8], 0usize);
            for_neighbours((j, k), (m, nphi), true, |i| {
                vals[n] = b[i];
                n += 1;
            });
            if n < 2 {
                continue;
            }
            let mean = vals[..n].iter().sum::<f64>() / n as f64;
            let var = vals[..n]
                .iter()
                .map(|v| (v - mean) * (v - mean))
                .sum::<f64>()
                / n as f64;
            out[j * nphi + k] = var.sqrt();
        }
    }
    out
}

/// Translational and rotational gradients of the hemisphere integral (in the same units as
/// the mean of `l`) for cells stratified as in [`super::sample`]: `l[j*nphi + k]` and distances.
/// Formulas of Ward & Heckbert (1992), "Irradiance Gradients", divided by π because the
/// values here are mean radiance rather than irradiance.
pub fn gradients(
    l: &[f64],
    r: &[f64],
    m: usize,
    nphi: usize,
    u: DVec3,
    v: DVec3,
) -> (DVec3, DVec3) {
    let mut gt = DVec3::ZERO;
    let mut gr = DVec3::ZERO;
    let at = |j: usize, k: usize| j * nphi + k;
    for k in 0..nphi {
        let phi_c = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
        let phi_b = 2.0 * PI * k as f64 / nphi as f64;
        let uk = u * phi_c.cos() + v * phi_c.sin();
        let vk_c = u * (phi_c + PI / 2.0).cos() + v * (phi_c + PI / 2.0).sin();
        let vk_b = u * (phi_b + PI / 2.0).cos() + v * (phi_b + PI / 2.0).sin();
        let km = (k + nphi - 1) % nphi;
        // Across θ boundaries (between rings j-1 and j).
        let mut a = 0.0;
        for j in 1..m {
            let s2 = j as f64 / m as f64;
            let sin_b = s2.sqrt();
            let cos2_b = 1.0 - s2;
            let rmin = r[at(j, k)].min(r[at(j - 1, k)]);
            a += sin_b * cos2_b / rmin * (l[at(j, k)] - l[at(j - 1, k)]);
        }
        gt += uk * (2.0 * PI / nphi as f64 * a);
        // Across φ boundaries (between columns k-1 and k).
        let mut b = 0.0;
        for j in 0..m {
            let sin_lo = (j as f64 / m as f64).sqrt();
            let sin_hi = ((j + 1) as f64 / m as f64).sqrt();
            let rmin = r[at(j, k)].min(r[at(j, km)]);
            b += (sin_hi - sin_lo) / rmin * (l[at(j, k)] - l[at(j, km)]);
        }
        gt += vk_b * b;
        // Rotational: Σ_j tanθ_j L_jk along v_k.
        let mut c = 0.0;
        for j in 0..m {
            let s2 = (j as f64 + 0.5) / m as f64;
            let tan = (s2 / (1.0 - s2).max(1e-12)).sqrt();
            c += tan * l[at(j, k)];
        }
        gr += vk_c * c;
    }
    let n = (m * nphi) as f64;
    (gt / PI, gr * (PI / n) / PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ambient::settings::OUTLIER_LIMIT;
    use crate::color::bright;

    #[test]
    fn unbiased_shares_never_read_the_cells_own_sample() {
        // Rings of 1 to 3 columns meet the wrapping's duplicates; 9 x 28 is a value's mesh.
        for (m, nphi) in [(4, 1), (4, 2), (3, 3), (9, 28)] {
            let mut b: Vec<f64> = (0..m * nphi)
                .map(|i| ((i * 7919) % 101) as f64 / 10.0)
                .collect();
            let base = super_sample_shares_unbiased(&b, m, nphi);
            for c in 0..m * nphi {
                let keep = b[c];
                b[c] = keep * 50.0 + 3.0;
                let s = super_sample_shares_unbiased(&b, m, nphi);
                b[c] = keep;
                assert_eq!(s[c], base[c], "cell {c} of {m}x{nphi}");
            }
        }
        // A lone bright cell: the cells around it share, it does not.
        let (m, nphi) = (5, 12);
        let mut b = vec![1.0; m * nphi];
        b[2 * nphi + 5] = 100.0;
        let s = super_sample_shares_unbiased(&b, m, nphi);
        assert_eq!(s[2 * nphi + 5], 0.0);
        for (dj, dk) in [(-1i64, -1i64), (-1, 0), (0, 1), (1, 1)] {
            let i = ((2 + dj) as usize) * nphi + (5 + dk) as usize;
            assert!(s[i] > 10.0, "neighbour {i}: {}", s[i]);
        }
        assert_eq!(s[0], 0.0);
    }

    #[test]
    fn one_dominant_cell_is_clamped_to_the_others_sum() {
        let grey = |x: f64| Color::splat(x);
        let clamp = |cells: &mut [Color], f: f64| {
            let mut b: Vec<f64> = cells.iter().map(|c| bright(*c)).collect();
            clamp_outliers(cells, &mut b, f);
            // The brightness is scaled with the colours.
            for (c, bi) in cells.iter().zip(&b) {
                assert!((bright(*c) - bi).abs() <= 1e-12 * bi.abs().max(1e-300));
            }
        };
        // 51 cells of 0.003 and one highlight of 9 (the spheres case): the highlight may
        // bring at most f × 51 × 0.003.
        let mut cells = vec![grey(0.003); 52];
        cells[17] = Color::new(18.0, 9.0, 0.0);
        let before = bright(cells[17]);
        clamp(&mut cells, 1.0);
        let others = 51.0 * bright(grey(0.003));
        assert!((bright(cells[17]) - others).abs() < 1e-12 * others);
        // Its colour keeps its proportions; the other cells are untouched.
        assert!((cells[17].x / cells[17].y - 2.0).abs() < 1e-12 && cells[17].z == 0.0);
        assert!(cells
            .iter()
            .enumerate()
            .all(|(i, c)| i == 17 || *c == grey(0.003)));
        assert!(bright(cells[17]) < before);
        // A bright but not dominant region (a window over 8 of 52 cells) is left alone.
        let mut window = vec![grey(0.01); 52];
        for c in &mut window[20..28] {
            *c = grey(2.0);
        }
        let copy = window.clone();
        clamp(&mut window, 1.0);
        assert_eq!(window, copy);
        // Black and single-cell hemispheres are left alone.
        let mut black = vec![Color::ZERO; 9];
        clamp(&mut black, 1.0);
        assert!(black.iter().all(|c| *c == Color::ZERO));
        let mut one = vec![grey(5.0)];
        clamp(&mut one, 1.0);
        assert_eq!(one[0], grey(5.0));
    }

    #[test]
    fn the_outlier_limit_loosens_with_the_sample_count() {
        // Up to 128 samples the limit is the base factor; at 4× the samples it is twice it.
        assert_eq!(outlier_limit(2.0, 50), 2.0);
        assert_eq!(outlier_limit(2.0, 128), 2.0);
        assert!((outlier_limit(2.0, 512) - 4.0).abs() < 1e-12);
        assert!(outlier_limit(2.0, 1500) > outlier_limit(2.0, 1000));
        // A spike of 3× the other cells' sum: cut in a value of 120 samples, kept whole in
        // one of 600 (a caustic there is caught often enough to be averaged, not removed).
        let spike = |n: usize| {
            let mut cells = vec![Color::splat(0.01); n];
            cells[3] = Color::splat(0.03 * (n - 1) as f64);
            let mut b: Vec<f64> = cells.iter().map(|c| bright(*c)).collect();
            let before = b[3];
            clamp_outliers(&mut cells, &mut b, outlier_limit(OUTLIER_LIMIT, n as u64));
            b[3] / before
        };
        assert!(spike(120) < 0.7);
        assert_eq!(spike(600), 1.0);
    }
}
