//! Unit tests of source sampling (`light::source`).

use super::*;

#[test]
fn square_to_disk_is_area_preserving() {
    // Uniform grid on the square maps to points whose radius² is uniform.
    let n = 200;
    let mut sum_r2 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = square_to_disk((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            assert!(x * x + y * y <= 1.0 + 1e-12);
            sum_r2 += x * x + y * y;
        }
    }
    let mean = sum_r2 / (n * n) as f64;
    assert!((mean - 0.5).abs() < 1e-3, "{mean}");
}

#[test]
fn cone_dir_stays_in_cone() {
    let axis = DVec3::new(1.0, 2.0, 3.0).normalize();
    let cos_max = 0.9;
    for i in 0..50 {
        for j in 0..50 {
            let d = cone_dir(axis, cos_max, i as f64 / 50.0, j as f64 / 50.0);
            assert!((d.length() - 1.0).abs() < 1e-12);
            assert!(d.dot(axis) >= cos_max - 1e-9);
        }
    }
}

#[test]
fn flat_partitions_agree_with_partitions() {
    // Sizes and distances around every threshold a shading point can meet (including
    // sizes within rounding of `thr · d`), and the degenerate ones.
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let eps = 1e-6;
    for k in 0..200_000 {
        let ds = [0.0, 0.1, 0.2, 0.25, 0.5, 1.0][k % 6];
        let weight = [1.0, 0.5, 1e-2, 1e-3, 1e-5][(k / 6) % 5];
        let d = 10f64.powf(next() * 8.0 - 5.0);
        let thr = ds / f64::clamp(weight, 1e-3, 1.0);
        let su = match k % 4 {
            // Right at the threshold, give or take a few units in the last place.
            0 => f64::from_bits(
                (thr * d)
                    .to_bits()
                    .wrapping_add((k as u64 % 7).wrapping_sub(3)),
            ),
            1 => thr * d * (0.5 + next()),
            2 => 10f64.powf(next() * 8.0 - 5.0),
            _ => [0.0, f64::INFINITY, f64::NAN, eps][(k / 4) % 4],
        };
        let sv = su * next();
        let d2 = d * d;
        let exact = {
            let d = d2.sqrt().max(eps);
            partitions(su / d, sv / d, ds, weight)
        };
        assert_eq!(
            flat_partitions((su, sv), d2, eps, (ds, weight)),
            exact,
            "su {su:e} sv {sv:e} d2 {d2:e} ds {ds} weight {weight}"
        );
    }
    // Within eps of the source the distance is eps.
    assert_eq!(
        flat_partitions((1e-6, 1e-6), 0.0, 1e-6, (0.25, 1.0)),
        partitions(1.0, 1.0, 0.25, 1.0)
    );
}

#[test]
fn partitions_limited() {
    assert_eq!(partitions(1.0, 1.0, 0.0, 1.0), (1, 1));
    assert_eq!(partitions(10.0, 10.0, 0.25, 1.0), (8, 8));
    assert_eq!(partitions(0.01, 0.01, 0.25, 1.0), (1, 1));
    // Radiance's counts for a square source at distance 5 (measured with rpict -dt 0):
    assert_eq!(partitions(0.2, 0.2, 0.25, 1.0), (1, 1));
    assert_eq!(partitions(0.4, 0.4, 0.25, 1.0), (2, 2));
    assert_eq!(partitions(0.8, 0.8, 0.25, 1.0), (4, 4));
    assert_eq!(partitions(0.2, 0.2, 0.1, 1.0), (2, 2));
    assert_eq!(partitions(0.4, 0.4, 0.5, 1.0), (1, 1));
}
