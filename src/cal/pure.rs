//! Pure expressions: a definition's whole meaning as one list of small steps, evaluated
//! without the run-time machine.
//!
//! Most expressions of a scene's patterns are small pure functions of the ray channels and
//! the primitive's real arguments: an ies2rad luminaire's `src_theta` (`Acos(Dz)/DEGREE`)
//! and `flatcorr(v)` (`corr(v)/Rdot`), a sky's `skybr`, a texture's coordinates. Evaluating
//! them through [`super::Program::begin`] costs a cache lookup, a tick, and a machine frame
//! per block, several times the arithmetic. [`Pure`] is the same expression with every
//! variable and every call of a defined function replaced by its definition (parameters by
//! their arguments), down to numbers, channels, the call's own values, `arg`, and library
//! functions, as steps (children before parents) that fill an array of values. A variable
//! is computed once, and so is each argument of a call; a variable first met inside a
//! branch of `if` or `select` is computed again if it is read after the branch (the branch
//! may be skipped). Pure means: nothing of the evaluation but the channels, the real
//! arguments and the call's values changes the result, so computing a value again, or
//! computing a branch the machine would not take, gives the same values bit for bit,
//! through the same `f64` operations in the same order and the same library functions.
//! Branches with a library call are skipped by forward jumps when not taken
//! ([`Step::Unless`], [`Step::Switch`]); branches of a few cheap steps are computed either
//! way ([`CHEAP_BRANCHES`]).
//!
//! An expression is not made pure ([`super::Program::pure_expr`] returns None) when it
//! reaches a function-name argument, a BRDF variable, an undefined name, a
//! variable called as a function or a function used as a variable, recursion deeper than
//! [`MAX_DEPTH`], or more than [`MAX_NODES`] nodes in all. Evaluation ([`Pure::eval`])
//! gives up (None) wherever the machine could raise an error: a result that is not finite,
//! a division by zero, `arg(n)` past the real arguments, a parameter the call did not
//! pass. The caller then evaluates by the machine, which gives the error exactly as before:
//! the pure path only ever returns values the machine returns.

use super::code::{Callee, Code, Def, Node, NodeId, Op, SlotId};
use super::eval::{better, noise_fn, select_index};
use super::library::Lib;
use std::collections::HashMap;

mod lanes;
pub use lanes::{LaneInputs, LANES};

/// Most nodes of a pure expression (larger ones stay with the machine).
pub const MAX_NODES: usize = 256;

/// Deepest nesting of definitions expanded into a pure expression.
pub const MAX_DEPTH: u32 = 48;

/// Most expressions in one pure form (a data file's dimensions).
pub const MAX_ROOTS: usize = 6;

/// Most steps of the two branches of an `if` computed both, without jumps, when all of
/// them are cheap ([`cheap`]).
const CHEAP_BRANCHES: usize = 8;

/// Whether a step costs no more than a jump: arithmetic without a library call.
fn cheap(s: &Step) -> bool {
    matches!(
        s,
        Step::Val(
            _,
            P::Chan(_)
                | P::Param(_)
                | P::Neg(_)
                | P::Add(..)
                | P::Sub(..)
                | P::Mul(..)
                | P::Div(..)
                | P::If(..)
                | P::Arg(_)
        )
    )
}

/// Expressions of at most this many nodes are evaluated in a buffer on the stack, of the
/// first of these sizes that holds them (a small buffer is copied inline, not by `memcpy`).
const SMALL: usize = 32;
const TIERS: [usize; 3] = [8, 16, SMALL];

/// One node of a pure expression; children are indices into [`Pure::nodes`], always
/// smaller than the node's own index (the root is the last).
#[derive(Debug, Clone, Copy)]
enum P {
    Num(f64),
    /// Ray channel index (0-based, below 27).
    Chan(u32),
    /// The call's value `i`.
    Param(u32),
    Neg(u32),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Pow(u32, u32),
    If(u32, u32, u32),
    /// A library function of one argument (its plain math, [`Lib::unary`]).
    Unary(fn(f64) -> f64, u32),
    Atan2(u32, u32),
    /// `min` or `max` (true) over a run of [`Pure::list`].
    MinMax(bool, u32, u16),
    /// `select` over a run of [`Pure::list`] (the index first).
    Select(u32, u16),
    Noise(Lib, u32, u32, u32),
    Arg(u32),
}

/// One step of an evaluation: a node's value, or a forward jump past the branches of an
/// `if` or `select` that are not taken.
#[derive(Debug, Clone, Copy)]
enum Step {
    /// Compute node `k`.
    Val(u32, P),
    /// Unless node `c` is above 0, go to step `to` (the `if`'s second branch).
    Unless(u32, u32),
    /// Go to step `to`.
    Goto(u32),
    /// Go to the step [`Pure::jumps`]`[at + k - 1]` of the argument `k` that node `c`
    /// selects among `n`, or to `jumps[at + n]` (the end) when it selects none.
    Switch(u32, u32, u32),
}

/// A pure expression (see the module documentation).
#[derive(Debug, Clone)]
pub struct Pure {
    /// Number of nodes.
    count: usize,
    /// Argument runs of `min`, `max` and `select`.
    list: Vec<u32>,
    /// Targets of [`Step::Switch`].
    jumps: Vec<u32>,
    /// What an evaluation starts from: each number node's value (0 elsewhere), padded with
    /// zeros to the size of its buffer ([`TIERS`]) for a form of at most [`SMALL`] nodes.
    init: Vec<f64>,
    /// The steps, in order; every jump goes forward.
    ops: Vec<Step>,
    /// The expressions' nodes (one or more roots).
    roots: Vec<u32>,
    /// Whether there are no jump steps (the simpler loop).
    straight: bool,
    /// The ray channels the steps read: bit `c` for channel `c` (0-based).
    chans: u32,
}

/// Expansion state: the code, the node budget and the variables expanded so far.
struct Expand<'a> {
    code: &'a Code,
    out: Pure,
    /// Each variable's node: a variable read several times (within an expression or by
    /// several roots) is computed once, as the machine computes it once per evaluation.
    vars: HashMap<SlotId, u32>,
    /// The real arguments every evaluation will pass, when known at expansion (a
    /// primitive's own): `arg(n)` of a number is then a number.
    args: Option<&'a [f64]>,
    /// Which nodes are numbers (in [`Pure::init`], computed by no step).
    konst: Vec<bool>,
}

impl Expand<'_> {
    /// A new node: a number goes into the initial values, anything else becomes a step,
    /// except that an operation of numbers alone is a number ([`Expand::fold`]).
    fn push(&mut self, p: P) -> Option<u32> {
        let p = self.fold(p).map_or(p, P::Num);
        let k = self.out.count;
        if k >= MAX_NODES {
            return None;
        }
        self.out.count += 1;
        match p {
            P::Num(x) => {
                self.out.init.push(x);
                self.konst.push(true);
            }
            _ => {
                self.out.init.push(0.0);
                self.konst.push(false);
                self.out.ops.push(Step::Val(k as u32, p));
            }
        }
        Some(k as u32)
    }

    /// The number node `k` stands for, if it is one.
    fn number(&self, k: u32) -> Option<f64> {
        match self.konst.get(k as usize) {
            Some(true) => self.out.init.get(k as usize).copied(),
            _ => None,
        }
    }

    /// The value of an operation whose operands are all numbers (and `arg(n)` of a number
    /// when the arguments are known), computed now by [`Pure::value`] itself: every
    /// evaluation would compute the same `f64` operations on the same numbers, so the
    /// values stay bit for bit the machine's. None for anything else, and for a result the
    /// machine would refuse (NaN here), which stays a step so that evaluations give up as
    /// before.
    fn fold(&self, p: P) -> Option<f64> {
        let all = |ks: &[u32]| ks.iter().all(|&k| self.number(k).is_some());
        let foldable = match p {
            P::Neg(a) | P::Unary(_, a) => all(&[a]),
            P::Add(a, b) | P::Sub(a, b) | P::Mul(a, b) | P::Div(a, b) | P::Pow(a, b) => {
                all(&[a, b])
            }
            P::Atan2(y, x) => all(&[y, x]),
            P::Arg(a) => self.args.is_some() && all(&[a]),
            _ => false,
        };
        if !foldable {
            return None;
        }
        let mut v = [0.0f64; MAX_NODES];
        let n = self.out.init.len().min(MAX_NODES);
        v[..n].copy_from_slice(&self.out.init[..n]);
        let r = self
            .out
            .value(p, &v, &[0.0; 27], self.args.unwrap_or(&[]), &[]);
        (!r.is_nan()).then_some(r)
    }

    /// A jump step to be aimed later ([`Expand::aim`]); its index.
    fn jump(&mut self, s: Step) -> usize {
        self.out.ops.push(s);
        self.out.ops.len() - 1
    }

    /// Aim jump step `j` at the next step.
    fn aim(&mut self, j: usize) {
        let here = self.out.ops.len() as u32;
        match &mut self.out.ops[j] {
            Step::Unless(_, to) | Step::Goto(to) => *to = here,
            _ => {}
        }
    }

    /// Argument `k` expanded as a branch taken only sometimes: variables first met in it
    /// are forgotten after it (their nodes are computed only when it is taken).
    fn branch(
        &mut self,
        args: &[NodeId],
        k: usize,
        params: Option<&[u32]>,
        depth: u32,
    ) -> Option<u32> {
        let saved = self.vars.clone();
        let r = self.node(*args.get(k)?, params, depth + 1);
        self.vars = saved;
        r
    }

    /// Node `n` of the code with parameters bound to `params` (pure node ids; None at the
    /// top of a function: its parameters are the call's values).
    fn node(&mut self, n: NodeId, params: Option<&[u32]>, depth: u32) -> Option<u32> {
        if depth > MAX_DEPTH {
            return None;
        }
        match *self.code.nodes.get(n as usize)? {
            Node::Num(v) => self.push(P::Num(v)),
            Node::Chan(c) => {
                let c = c.checked_sub(1)?;
                (c < 27).then_some(())?;
                self.push(P::Chan(c))
            }
            Node::Param(i) => match params {
                Some(p) => p.get(i as usize).copied(),
                None => self.push(P::Param(u32::from(i))),
            },
            Node::Neg(a) => {
                let a = self.node(a, params, depth + 1)?;
                self.push(P::Neg(a))
            }
            Node::Bin(op, a, b) => {
                let a = self.node(a, params, depth + 1)?;
                let b = self.node(b, params, depth + 1)?;
                self.push(match op {
                    Op::Add => P::Add(a, b),
                    Op::Sub => P::Sub(a, b),
                    Op::Mul => P::Mul(a, b),
                    Op::Div => P::Div(a, b),
                    Op::Pow => P::Pow(a, b),
                })
            }
            Node::Var(s) => match self.code.slots.get(s as usize)?.def {
                Def::Num(v) => self.push(P::Num(v)),
                Def::Var { expr, .. } => {
                    if let Some(&k) = self.vars.get(&s) {
                        return Some(k);
                    }
                    let k = self.node(expr, Some(&[]), depth + 1)?;
                    self.vars.insert(s, k);
                    Some(k)
                }
                _ => None,
            },
            Node::Call { callee, first, n } => {
                let args = self
                    .code
                    .arglist
                    .get(first as usize..first as usize + n as usize)?;
                match callee {
                    Callee::Lib(l) => self.lib(l, args, params, depth),
                    Callee::Slot(s) => {
                        let slot = self.code.slots.get(s as usize)?;
                        match slot.def {
                            Def::Func { nparams, body, .. } => {
                                // Every parameter the body may read is bound (a missing
                                // one is the machine's fatal error: not pure).
                                if (n as usize) < nparams as usize {
                                    return None;
                                }
                                let mut bound = Vec::with_capacity(args.len());
                                for &a in args {
                                    bound.push(self.node(a, params, depth + 1)?);
                                }
                                self.node(body, Some(&bound), depth + 1)
                            }
                            Def::None => self.lib(slot.lib?, args, params, depth),
                            _ => None,
                        }
                    }
                    Callee::Param(_) => None,
                }
            }
        }
    }

    fn lib(&mut self, l: Lib, args: &[NodeId], params: Option<&[u32]>, depth: u32) -> Option<u32> {
        let a = |k: usize, me: &mut Self| me.node(*args.get(k)?, params, depth + 1);
        match l {
            Lib::If => {
                if args.len() < 3 {
                    return None;
                }
                let c = a(0, self)?;
                // A condition that is a number takes its branch alone, as every evaluation
                // would (a NaN one stays, for the `if` to refuse).
                if let Some(x) = self.number(c).filter(|x| !x.is_nan()) {
                    return a(if x > 0.0 { 1 } else { 2 }, self);
                }
                let j = self.jump(Step::Unless(c, 0));
                let x = self.branch(args, 1, params, depth)?;
                let g = self.jump(Step::Goto(0));
                self.aim(j);
                let y = self.branch(args, 2, params, depth)?;
                self.aim(g);
                // Branches of a few cheap steps are computed both, without jumps (what
                // the jumps save is less than they cost; `bound`, `abs`, `corr`).
                let inside = self.out.ops[j + 1..g].iter().chain(&self.out.ops[g + 1..]);
                if inside.clone().count() <= CHEAP_BRANCHES && inside.clone().all(cheap) {
                    self.out.ops.remove(g);
                    self.out.ops.remove(j);
                }
                self.push(P::If(c, x, y))
            }
            Lib::Atan2 => {
                let y = a(0, self)?;
                let x = a(1, self)?;
                self.push(P::Atan2(y, x))
            }
            Lib::Min | Lib::Max => {
                if args.is_empty() || args.len() > u16::MAX as usize {
                    return None;
                }
                let mut ids = Vec::with_capacity(args.len());
                for k in 0..args.len() {
                    ids.push(a(k, self)?);
                }
                let at = self.out.list.len() as u32;
                self.out.list.extend(ids);
                self.push(P::MinMax(l == Lib::Max, at, args.len() as u16))
            }
            Lib::Arg => {
                let x = a(0, self)?;
                self.push(P::Arg(x))
            }
            Lib::Noise3 | Lib::Noise3x | Lib::Noise3y | Lib::Noise3z | Lib::Fnoise3 => {
                let x = a(0, self)?;
                let y = a(1, self)?;
                let z = a(2, self)?;
                self.push(P::Noise(l, x, y, z))
            }
            Lib::Select => {
                if args.is_empty() || args.len() > u16::MAX as usize {
                    return None;
                }
                let n = args.len() - 1;
                let c = a(0, self)?;
                let table = self.out.jumps.len();
                self.out.jumps.resize(table + n + 1, 0);
                self.jump(Step::Switch(c, table as u32, n as u32));
                let mut ids = vec![c];
                let mut gotos = Vec::with_capacity(n);
                for k in 1..=n {
                    self.out.jumps[table + k - 1] = self.out.ops.len() as u32;
                    ids.push(self.branch(args, k, params, depth)?);
                    gotos.push(self.jump(Step::Goto(0)));
                }
                for g in gotos {
                    self.aim(g);
                }
                self.out.jumps[table + n] = self.out.ops.len() as u32;
                let at = self.out.list.len() as u32;
                self.out.list.extend(ids);
                self.push(P::Select(at, args.len() as u16))
            }
            _ => {
                let f = l.unary()?;
                let x = a(0, self)?;
                self.push(P::Unary(f, x))
            }
        }
    }
}

/// The pure form of nodes `roots` of `code`: expressions when `function` is false (they
/// have no parameters), one function's body when true (its parameters are the call's
/// values).
pub(crate) fn expand(
    code: &Code,
    roots: &[NodeId],
    function: bool,
    args: Option<&[f64]>,
) -> Option<Pure> {
    let mut e = Expand {
        args,
        konst: Vec::new(),
        code,
        out: Pure {
            count: 0,
            list: Vec::new(),
            jumps: Vec::new(),
            init: Vec::new(),
            ops: Vec::new(),
            roots: Vec::new(),
            straight: false,
            chans: 0,
        },
        vars: HashMap::new(),
    };
    let params: Option<&[u32]> = if function { None } else { Some(&[]) };
    if roots.is_empty() || roots.len() > MAX_ROOTS {
        return None;
    }
    for &r in roots {
        let top = e.node(r, params, 0)?;
        e.out.roots.push(top);
    }
    let mut out = e.out;
    // A small form's initial values fill the whole stack buffer, which an evaluation then
    // takes in one fixed-size copy (rather than zeroing it and copying the numbers).
    if let Some(&size) = TIERS.iter().find(|&&t| out.count <= t) {
        out.init.resize(size, 0.0);
    }
    out.straight = out.ops.iter().all(|s| matches!(s, Step::Val(..)));
    out.chans = out.ops.iter().fold(0, |m, s| match s {
        Step::Val(_, P::Chan(c)) if *c < 32 => m | 1 << c,
        _ => m,
    });
    Some(out)
}

impl Pure {
    /// The ray channels an evaluation reads (bit `c` for channel `c`, 0-based): the others
    /// may hold anything ([`crate::modifier::frame::PatternFrame::channels_for`]).
    pub fn channels_read(&self) -> u32 {
        self.chans
    }

    /// The value for ray channels `chan`, real arguments `args` and the call's values
    /// `values` (of the first root); None wherever the machine could raise an error (see
    /// the module documentation).
    pub fn eval(&self, chan: &[f64; 27], args: &[f64], values: &[f64]) -> Option<f64> {
        let mut out = [0.0];
        self.eval_into(chan, args, values, &mut out)?;
        Some(out[0])
    }

    /// The values of the roots (as many as `out` holds, at most the roots), or None when
    /// any of them is left to the machine.
    pub fn eval_into(
        &self,
        chan: &[f64; 27],
        args: &[f64],
        values: &[f64],
        out: &mut [f64],
    ) -> Option<()> {
        if self.count == 0 || out.len() > self.roots.len() {
            return None;
        }
        if self.count <= TIERS[0] {
            let mut v: [f64; TIERS[0]] = self.init.get(..TIERS[0])?.try_into().ok()?;
            self.fill(&mut v, chan, args, values, out)
        } else if self.count <= TIERS[1] {
            let mut v: [f64; TIERS[1]] = self.init.get(..TIERS[1])?.try_into().ok()?;
            self.fill(&mut v, chan, args, values, out)
        } else if self.count <= SMALL {
            let mut v: [f64; SMALL] = self.init.get(..SMALL)?.try_into().ok()?;
            self.fill(&mut v, chan, args, values, out)
        } else {
            let mut v = [0.0f64; MAX_NODES];
            v[..self.init.len()].copy_from_slice(&self.init);
            self.fill(&mut v, chan, args, values, out)
        }
    }

    /// Evaluate in a buffer of N values holding the initial values (a power of two at least
    /// the node count: indices are masked by N − 1, which needs no bounds checks) and read
    /// the roots; None unless all are finite.
    fn fill<const N: usize>(
        &self,
        v: &mut [f64; N],
        chan: &[f64; 27],
        args: &[f64],
        values: &[f64],
        out: &mut [f64],
    ) -> Option<()> {
        const { assert!(N.is_power_of_two()) };
        if self.straight {
            self.run_straight(v, chan, args, values);
        } else {
            self.run(v, chan, args, values);
        }
        for (o, &r) in out.iter_mut().zip(&self.roots) {
            let x = v[r as usize & (N - 1)];
            if !x.is_finite() {
                return None;
            }
            *o = x;
        }
        Some(())
    }

    /// The steps in order (children come before their parents), jumps included, over the
    /// values `v` (numbers already in place). A node the machine would refuse (a NaN or
    /// infinite library result, a division by zero, `arg(n)` or a parameter past the end)
    /// or carry on with (an infinite sum) is NaN here, and so is every node computed from
    /// it; a root is NaN exactly when it depends on one. A branch skipped by a jump, or
    /// computed and not taken, is never read, as the machine never evaluates it.
    fn run<const N: usize>(
        &self,
        v: &mut [f64; N],
        chan: &[f64; 27],
        args: &[f64],
        values: &[f64],
    ) {
        let mut pc = 0;
        while let Some(&step) = self.ops.get(pc) {
            pc += 1;
            let (k, node) = match step {
                Step::Val(k, p) => (k, p),
                Step::Unless(c, to) => {
                    // A NaN condition goes either way: the `if` refuses it.
                    let c = v[c as usize & (N - 1)];
                    if c.is_nan() || c <= 0.0 {
                        pc = to as usize;
                    }
                    continue;
                }
                Step::Goto(to) => {
                    pc = to as usize;
                    continue;
                }
                Step::Switch(c, at, n) => {
                    let d = v[c as usize & (N - 1)] + 0.5;
                    let k = match select_index(d, n as usize) {
                        Ok(k) if k >= 1 => k - 1,
                        _ => n as usize,
                    };
                    pc = self.jumps[at as usize + k] as usize;
                    continue;
                }
            };
            v[k as usize & (N - 1)] = self.value(node, v, chan, args, values);
        }
    }

    /// Every node in order, when there are no jumps (see [`Pure::run`]).
    fn run_straight<const N: usize>(
        &self,
        v: &mut [f64; N],
        chan: &[f64; 27],
        args: &[f64],
        values: &[f64],
    ) {
        for step in &self.ops {
            if let Step::Val(k, node) = *step {
                v[k as usize & (N - 1)] = self.value(node, v, chan, args, values);
            }
        }
    }

    /// Node `node`'s value from the values `v` of its children; NaN where the machine
    /// would refuse it (see [`Pure::run`]): the lanes' rule ([`Pure::value_lanes`]) at one.
    #[inline(always)]
    fn value<const N: usize>(
        &self,
        node: P,
        v: &[f64; N],
        chan: &[f64; 27],
        args: &[f64],
        values: &[f64],
    ) -> f64 {
        let [r] = self.value_lanes::<1>(
            node,
            |j, _| v[j as usize & (N - 1)],
            |c, _| chan.get(c as usize).copied().unwrap_or(f64::NAN),
            |p, _| values.get(p as usize).copied().unwrap_or(f64::NAN),
            args,
        );
        r
    }

    /// Number of steps an evaluation runs at most (for tests).
    #[cfg(test)]
    pub(crate) fn steps(&self) -> usize {
        self.ops.len()
    }

    /// Whether some branches are skipped by jumps (for tests).
    #[cfg(test)]
    pub(crate) fn has_jumps(&self) -> bool {
        !self.straight
    }
}
