//! The coincident-hit window of [`super::bvh::Bvh::closest`]: the hits within `eps` of the
//! closest one found so far, and the selection among them under the documented rule.

use std::mem::MaybeUninit;

use crate::FTINY;

/// Capacity of the coincident-hit window of [`super::bvh::Bvh::closest`].
pub const WINDOW: usize = 16;

/// Hits within `eps` of the closest one (fixed capacity, no allocation). Its storage is
/// left uninitialised until written: a search makes one window per tree it enters (every
/// instance placement a ray reaches), and zeroing its 256 bytes took a `memset` call each
/// time.
///
/// `repr(C)` with the storage last, next to `eps`: placed next to `len`'s zero, LLVM merged
/// the uninitialised bytes into one `memset` of both.
#[repr(C)]
pub(super) struct Window {
    len: usize,
    pub(super) tmin: f64,
    eps: f64,
    /// Entries `0..len` are written; the rest are not read.
    buf: [MaybeUninit<(usize, f64)>; WINDOW],
}

impl Window {
    pub(super) fn new(eps: f64) -> Self {
        Window {
            len: 0,
            tmin: f64::INFINITY,
            eps,
            buf: [MaybeUninit::uninit(); WINDOW],
        }
    }

    /// Entry `j`, which must be below `len`.
    #[inline]
    fn at(&self, j: usize) -> (usize, f64) {
        assert!(j < self.len);
        // SAFETY: every entry below `len` has been written (`put` is the only writer, and
        // `len` only grows over written entries or shrinks).
        unsafe { self.buf[j].assume_init() }
    }

    #[inline]
    fn put(&mut self, j: usize, v: (usize, f64)) {
        self.buf[j] = MaybeUninit::new(v);
    }

    /// Add a hit; returns true when it lowered the closest distance.
    pub(super) fn push(&mut self, i: usize, t: f64) -> bool {
        if t > self.tmin + self.eps {
            return false;
        }
        let lowered = t < self.tmin;
        if lowered {
            self.tmin = t;
            let lim = t + self.eps;
            let mut k = 0;
            for j in 0..self.len {
                let h = self.at(j);
                if h.1 <= lim {
                    self.put(k, h);
                    k += 1;
                }
            }
            self.len = k;
        }
        if self.len < WINDOW {
            self.put(self.len, (i, t));
            self.len += 1;
        } else {
            // Overflow: replace the farthest entry if the new one is nearer.
            let mut far = 0;
            for j in 1..WINDOW {
                if self.at(j).1 > self.at(far).1 {
                    far = j;
                }
            }
            if t < self.at(far).1 {
                self.put(far, (i, t));
            }
        }
        lowered
    }

    /// The winner under the documented rule.
    pub(super) fn select(&self, prefer: &impl Fn(usize, usize) -> bool) -> Option<(usize, f64)> {
        if self.len == 0 {
            return None;
        }
        let mut w = self.at(0);
        for j in 1..self.len {
            let c = self.at(j);
            if beats(c, w, prefer) {
                w = c;
            }
        }
        Some(w)
    }
}

/// True when hit `c` beats hit `w` (see the module documentation of [`super::bvh`]).
pub(super) fn beats(
    c: (usize, f64),
    w: (usize, f64),
    prefer: &impl Fn(usize, usize) -> bool,
) -> bool {
    let pc = prefer(c.0, w.0);
    let pw = prefer(w.0, c.0);
    if pc != pw {
        return pc;
    }
    (c.1, c.0) < (w.1, w.0)
}

/// Reference implementation of [`super::bvh::Bvh::closest`]'s selection over an explicit
/// list of hits `(index, t)` for a BVH built with `eps = FTINY` (hits outside `(FTINY,
/// tmax)` are ignored). Useful for brute-force checks.
pub fn select_closest(
    hits: impl IntoIterator<Item = (usize, f64)>,
    tmax: f64,
    prefer: impl Fn(usize, usize) -> bool,
) -> Option<(usize, f64)> {
    let mut win = Window::new(FTINY);
    for (i, t) in hits {
        if t > FTINY && t < tmax {
            win.push(i, t);
        }
    }
    win.select(&prefer)
}
