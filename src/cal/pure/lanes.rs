//! A pure expression evaluated for several points at once ([`Pure::eval_lanes`]): each step
//! computes its node for every lane before the next step, so the steps are decoded once
//! for all of them, and the lanes' library calls (an ies2rad luminaire's `acos`) follow
//! one another without the rest of the evaluation between them. Each lane's values are
//! the ones [`Pure::eval_into`] gives it alone, bit for bit: the same operations on the
//! same operands in the same order; [`Pure::value`] is this module's node rule at one
//! lane.

use super::{better, noise_fn, select_index, Pure, Step, P, SMALL};

/// Points evaluated together.
pub const LANES: usize = 8;

/// What the lanes of one evaluation read: ray channels, the call's values (`values` of
/// [`Pure::eval_into`], at most three) and how many of those there are.
pub struct LaneInputs<'a> {
    pub chans: &'a [[f64; 27]; LANES],
    pub values: &'a [[f64; 3]; LANES],
    pub nvalues: usize,
}

impl Pure {
    /// The roots' values (`out[lane][root]`, as many roots as `roots` says) at lanes
    /// `0..n`, with the real arguments `args` shared by all; `ok[lane]` is false where
    /// [`Pure::eval_into`] would give None. False (nothing done) for a form with jumps or
    /// more than the stack buffer's nodes, which the caller evaluates lane by lane.
    pub fn eval_lanes(
        &self,
        n: usize,
        input: &LaneInputs,
        args: &[f64],
        roots: usize,
        out: &mut [[f64; 3]; LANES],
        ok: &mut [bool; LANES],
    ) -> bool {
        if !self.straight
            || self.count == 0
            || self.count > SMALL
            || roots > self.roots.len()
            || roots > 3
            || n > LANES
        {
            return false;
        }
        // The fewest lanes that hold n (each lane's values are its own: the spare ones,
        // computed from whatever their inputs hold, are not read).
        let (at, to) = ((n, roots, args), (out, ok));
        match (self.count, n) {
            (0..=8, 0..=2) => self.lanes::<8, 2>(at, input, to),
            (0..=8, 3..=4) => self.lanes::<8, 4>(at, input, to),
            (0..=8, _) => self.lanes::<8, 8>(at, input, to),
            (9..=16, 0..=2) => self.lanes::<16, 2>(at, input, to),
            (9..=16, 3..=4) => self.lanes::<16, 4>(at, input, to),
            (9..=16, _) => self.lanes::<16, 8>(at, input, to),
            (_, 0..=2) => self.lanes::<SMALL, 2>(at, input, to),
            (_, 3..=4) => self.lanes::<SMALL, 4>(at, input, to),
            _ => self.lanes::<SMALL, 8>(at, input, to),
        }
        true
    }

    /// [`Pure::eval_lanes`] in a buffer of `N` nodes (a power of two at least the count)
    /// by `L` lanes (at least n, at most [`LANES`]).
    fn lanes<const N: usize, const L: usize>(
        &self,
        (n, roots, args): (usize, usize, &[f64]),
        input: &LaneInputs,
        (out, ok): (&mut [[f64; 3]; LANES], &mut [bool; LANES]),
    ) {
        const { assert!(N.is_power_of_two() && L <= LANES) };
        // The numbers in every lane; the other nodes are written before they are read.
        let mut v: [[f64; L]; N] =
            std::array::from_fn(|k| [self.init.get(k).copied().unwrap_or(0.0); L]);
        let nv = input.nvalues.min(3);
        for step in &self.ops {
            if let Step::Val(k, node) = *step {
                let r = self.value_lanes::<L>(
                    node,
                    |j, l| v[j as usize & (N - 1)][l],
                    |c, l| input.chans[l].get(c as usize).copied().unwrap_or(f64::NAN),
                    |p, l| match (p as usize) < nv {
                        true => input.values[l][p as usize],
                        false => f64::NAN,
                    },
                    args,
                );
                v[k as usize & (N - 1)] = r;
            }
        }
        for l in 0..n {
            ok[l] = true;
            for (i, &r) in self.roots[..roots].iter().enumerate() {
                let x = v[r as usize & (N - 1)][l];
                ok[l] &= x.is_finite();
                out[l][i] = x;
            }
        }
    }

    /// Node `node`'s value at each of `L` lanes from its children's values (`g(child,
    /// lane)`), the ray channels (`chan(index, lane)`) and the call's values (`param(index,
    /// lane)`, NaN where there is none); NaN where the machine would refuse it (see
    /// [`Pure::run`]).
    #[inline(always)]
    pub(super) fn value_lanes<const L: usize>(
        &self,
        node: P,
        g: impl Fn(u32, usize) -> f64,
        chan: impl Fn(u32, usize) -> f64,
        param: impl Fn(u32, usize) -> f64,
        args: &[f64],
    ) -> [f64; L] {
        let mut r = [0.0f64; L];
        macro_rules! each {
            (|$l:ident| $e:expr) => {
                for ($l, o) in r.iter_mut().enumerate() {
                    *o = $e;
                }
            };
        }
        // Both operands usable, else NaN.
        let two = |x: f64, y: f64, f: fn(f64, f64) -> f64| {
            if x.is_nan() || y.is_nan() {
                f64::NAN
            } else {
                f(x, y)
            }
        };
        match node {
            P::Num(x) => each!(|_l| x),
            P::Chan(c) => each!(|l| chan(c, l)),
            P::Param(p) => each!(|l| param(p, l)),
            P::Neg(a) => each!(|l| -g(a, l)),
            P::Add(a, b) => each!(|l| g(a, l) + g(b, l)),
            P::Sub(a, b) => each!(|l| g(a, l) - g(b, l)),
            P::Mul(a, b) => each!(|l| g(a, l) * g(b, l)),
            // A refused operand refuses the operation (`x^0` of a NaN is 1).
            P::Div(a, b) => each!(|l| two(g(a, l), g(b, l), |x, y| if y == 0.0 {
                f64::NAN
            } else {
                x / y
            })),
            P::Pow(a, b) => each!(|l| two(g(a, l), g(b, l), f64::powf)),
            P::If(c, a, b) => each!(|l| {
                let c = g(c, l);
                if c.is_nan() {
                    f64::NAN
                } else if c > 0.0 {
                    g(a, l)
                } else {
                    g(b, l)
                }
            }),
            P::Unary(f, a) => each!(|l| {
                let x = g(a, l);
                if x.is_nan() {
                    f64::NAN
                } else {
                    f(x)
                }
            }),
            P::Atan2(y, x) => each!(|l| two(g(y, l), g(x, l), f64::atan2)),
            P::MinMax(max, at, n) => {
                // From the last argument backwards, as the machine; a refused argument
                // refuses the whole call.
                let run = &self.list[at as usize..at as usize + n as usize];
                each!(|l| {
                    let mut best = g(run[run.len() - 1], l);
                    for &j in run[..run.len() - 1].iter().rev() {
                        let a = g(j, l);
                        best = if a.is_nan() { a } else { better(max, best, a) };
                    }
                    best
                })
            }
            P::Select(at, n) => {
                // The chosen argument (0: their count); a refused index or one out of
                // range is the machine's domain error. All were computed; the others are
                // dropped, as the machine never evaluates them.
                let run = &self.list[at as usize..at as usize + n as usize];
                let count = run.len() - 1;
                each!(|l| match select_index(g(run[0], l) + 0.5, count) {
                    Ok(0) => count as f64,
                    Ok(k) => g(run[k], l),
                    Err(_) => f64::NAN,
                })
            }
            P::Noise(f, x, y, z) => each!(|l| {
                let (x, y, z) = (g(x, l), g(y, l), g(z, l));
                if x.is_nan() || y.is_nan() || z.is_nan() {
                    f64::NAN
                } else {
                    noise_fn(f, x, y, z)
                }
            }),
            P::Arg(a) => each!(|l| {
                let x = g(a, l);
                let n = (x + 0.5) as i64;
                if x.is_nan() {
                    f64::NAN
                } else if n < 1 {
                    args.len() as f64
                } else {
                    args.get(n as usize - 1).copied().unwrap_or(f64::NAN)
                }
            }),
        }
        // Infinities (which the machine carries through sums) are refused too.
        for x in &mut r {
            if !x.is_finite() {
                *x = f64::NAN;
            }
        }
        r
    }
}
