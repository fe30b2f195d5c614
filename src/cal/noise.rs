//! The renderer's noise functions: `noise3` (Perlin's 2002 "improved noise"), its
//! finite-difference derivatives `noise3x/y/z`, and `fnoise3` (a deterministic midpoint
//! displacement fractal), as described in §1.7 of the format reference.

/// Ken Perlin's reference permutation (2002).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

fn p(i: usize) -> usize {
    PERM[i & 255] as usize
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(t: f64, a: f64, b: f64) -> f64 {
    a + t * (b - a)
}

fn grad(hash: usize, x: f64, y: f64, z: f64) -> f64 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// The cell index of a coordinate (masked by 255) and the offset within the cell. The
/// cell is a C int, as in Radiance: beyond its range (or for NaN) it is INT_MIN (x86's
/// conversion), so huge coordinates give huge offsets (and an infinite or NaN result).
fn cell(x: f64) -> (usize, f64) {
    let f = x.floor();
    let i = if (-2147483648.0..2147483648.0).contains(&f) {
        f as i32
    } else {
        i32::MIN
    };
    ((i & 255) as usize, x - i as f64)
}

/// Perlin's improved noise at (x, y, z), about in [−1, 1].
pub fn noise3(x: f64, y: f64, z: f64) -> f64 {
    let (xi, x) = cell(x);
    let (yi, y) = cell(y);
    let (zi, z) = cell(z);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let a = p(xi) + yi;
    let (aa, ab) = (p(a) + zi, p(a + 1) + zi);
    let b = p(xi + 1) + yi;
    let (ba, bb) = (p(b) + zi, p(b + 1) + zi);
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(p(aa), x, y, z), grad(p(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(p(ab), x, y - 1.0, z),
                grad(p(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(p(aa + 1), x, y, z - 1.0),
                grad(p(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(p(ab + 1), x, y - 1.0, z - 1.0),
                grad(p(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// The step of the derivatives.
const EPS: f64 = 0.0005;

/// `noise3x/y/z`: the backward difference of [`noise3`] along `axis` (0, 1, 2).
pub fn noise3_d(axis: usize, x: f64, y: f64, z: f64) -> f64 {
    let mut q = [x, y, z];
    q[axis] -= EPS;
    (noise3(x, y, z) - noise3(q[0], q[1], q[2])) / EPS
}

/// A hash of an integer to (−1, 1].
fn frand(s: i64) -> f64 {
    let s = (s << 13) ^ s;
    let h = s
        .wrapping_mul(s.wrapping_mul(s).wrapping_mul(15731).wrapping_add(789221))
        .wrapping_add(1376312589)
        & 0x7fff_ffff;
    1.0 - h as f64 / 1073741824.0
}

fn frand3(v: [i64; 3]) -> f64 {
    frand(
        v[0].wrapping_mul(17)
            .wrapping_add(v[1].wrapping_mul(23))
            .wrapping_add(v[2].wrapping_mul(29)),
    )
}

/// `fnoise3`: midpoint displacement over an integer lattice of 2000 steps per unit, about
/// in [−1, 1].
pub fn fnoise3(x: f64, y: f64, z: f64) -> f64 {
    let mut s: i64 = 2000;
    let xs = [x, y, z];
    // Saturating float → integer casts keep absurd coordinates harmless.
    let t: [i64; 3] = xs.map(|c| (s as f64 * c) as i64);
    let mut b: [i64; 3] = xs.map(|c| (s as f64 * c.floor()) as i64);
    let mut corner = [0.0f64; 8];
    for (j, c) in corner.iter_mut().enumerate() {
        let mut v = b;
        for (i, vi) in v.iter_mut().enumerate() {
            if j >> i & 1 == 1 {
                *vi = vi.wrapping_add(s);
            }
        }
        *c = frand3(v);
    }
    loop {
        let fc = corner.iter().sum::<f64>() / 8.0;
        s /= 2;
        if s == 0 {
            return fc;
        }
        let amp = s as f64 * EPS;
        let mut v = b.map(|bi| bi.wrapping_add(s));
        let mut branch = 0usize;
        for i in 0..3 {
            if t[i] > v[i] {
                branch |= 1 << i;
            }
        }
        let old = corner;
        corner[!branch & 7] = fc + amp * frand3(v);
        let toward = |v: &mut [i64; 3], i: usize| {
            if branch >> i & 1 == 1 {
                v[i] = v[i].wrapping_add(s);
            } else {
                v[i] = v[i].wrapping_sub(s);
            }
        };
        for i in 0..3 {
            let keep = v;
            toward(&mut v, i);
            let face: f64 = (0..8)
                .filter(|j| (j >> i & 1) == (branch >> i & 1))
                .map(|j| old[j])
                .sum();
            corner[!(branch ^ (1 << i)) & 7] = 0.25 * face + amp * frand3(v);
            v = keep;
        }
        for i in 0..3 {
            let keep = v;
            for k in (0..3).filter(|&k| k != i) {
                toward(&mut v, k);
            }
            let bit = 1 << i;
            corner[branch ^ bit] = 0.5 * (old[branch & !bit] + old[branch | bit]) + amp * frand3(v);
            v = keep;
        }
        for (i, bi) in b.iter_mut().enumerate() {
            if branch >> i & 1 == 1 {
                *bi = bi.wrapping_add(s);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_complete() {
        let mut v = PERM.to_vec();
        v.sort();
        assert!(v.iter().enumerate().all(|(i, &x)| i == x as usize));
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn verified_values() {
        // §1.10: rtrace 6.0a at three points.
        let pts = [
            ([0.5, 0.25, 0.0], [-0.0776367, -0.874999, -0.3119419]),
            ([1.3, 2.7, 0.0], [0.155537, -0.924818, -0.387185]),
            ([-3.21, 4.5, 0.0], [0.20397, -0.207128, -0.044879]),
        ];
        for (p, want) in pts {
            let got = [
                noise3(p[0], p[1], p[2]),
                noise3_d(0, p[0], p[1], p[2]),
                fnoise3(p[0], p[1], p[2]),
            ];
            for k in 0..3 {
                assert!(
                    close(got[k], want[k], 2e-6),
                    "{p:?} {k}: {} vs {}",
                    got[k],
                    want[k]
                );
            }
        }
    }
}
