//! The tree walker: a recursive walk over the node arena with lazy, per-call cached
//! arguments, per-evaluation cached variables and a depth limit. The builder uses it to
//! fold constants while compiling; a finished program runs on [`super::vm`], which keeps
//! these semantics and shares the error messages ([`describe`]).
//!
//! Errors travel as a small [`Trap`]; a fatal error's message is kept in the machine
//! until the public API turns it into [`super::EvalError::Fatal`].

use super::code::{Callee, Code, Def, Node, NodeId, Op, SlotId};
use super::library::Lib;
use super::noise;
use super::Env;
use std::cell::Cell;

/// The deepest nesting one evaluation may reach; deeper is the fatal error "recursion too
/// deep". The tree walker counts nested node evaluations (expression depth plus function
/// and variable calls, added up; about 600 KB of stack in a release build), the run-time
/// machine nested blocks (each a variable computed, a function called or an argument
/// evaluated; arithmetic does not nest there).
pub const MAX_DEPTH: u32 = 3000;

/// The stack one evaluation may use, whichever limit comes first (debug builds have much
/// larger frames): a runaway recursion is a fatal error, never a stack overflow, even on a
/// 2 MB thread.
pub const MAX_STACK: usize = 1 << 20;

/// An address on the current stack.
#[inline(always)]
pub(crate) fn stack_here() -> usize {
    let marker = 0u8;
    std::hint::black_box(&marker) as *const u8 as usize
}

/// Arguments cached per call (Radiance caches the first 10; later ones are re-evaluated on
/// each use, which is equivalent since evaluation has no side effects).
pub(crate) const NCACHE: usize = 8;

/// A run-time error inside the machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Trap {
    Domain,
    Range,
    /// The message is in [`Machine::fatal`].
    Fatal,
}

pub(crate) type R = Result<f64, Trap>;

/// A cached variable value: valid when `tick` is the evaluation's tick.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Entry {
    pub tick: u64,
    pub value: f64,
}

/// Where a call's arguments come from.
#[derive(Clone, Copy)]
pub(crate) enum ArgSrc<'f> {
    /// No arguments (a variable or top-level expression).
    None,
    /// Argument expressions, evaluated lazily in the caller's frame.
    Nodes {
        list: &'f [NodeId],
        caller: &'f Frame<'f>,
    },
    /// Values given by the host program.
    Values(&'f [f64]),
}

impl ArgSrc<'_> {
    pub fn len(&self) -> usize {
        match self {
            ArgSrc::None => 0,
            ArgSrc::Nodes { list, .. } => list.len(),
            ArgSrc::Values(v) => v.len(),
        }
    }
}

/// One function call's frame.
pub(crate) struct Frame<'f> {
    pub src: ArgSrc<'f>,
    /// The function called (for messages); u32::MAX at top level.
    pub func: SlotId,
    /// Bit i: parameter i is in `vals[i]`.
    pub done: Cell<u32>,
    pub vals: [Cell<f64>; NCACHE],
}

impl<'f> Frame<'f> {
    pub fn new(src: ArgSrc<'f>, func: SlotId) -> Frame<'f> {
        Frame {
            src,
            func,
            done: Cell::new(0),
            vals: Default::default(),
        }
    }

    pub fn top() -> Frame<'static> {
        Frame::new(ArgSrc::None, u32::MAX)
    }
}

/// The evaluator's state for one evaluation.
pub(crate) struct Machine<'a> {
    pub code: &'a Code,
    /// None: constant mode (folding while compiling), where ray data is an error.
    pub env: Option<&'a Env<'a>>,
    pub cache: &'a mut [Entry],
    pub tick: u64,
    pub depth: u32,
    /// [`stack_here`] where the evaluation started.
    pub stack: usize,
    pub fatal: Option<String>,
}

pub(crate) fn check(v: f64) -> R {
    if v.is_nan() {
        Err(Trap::Domain)
    } else if v.is_infinite() {
        Err(Trap::Range)
    } else {
        Ok(v)
    }
}

/// A fatal error, described when it happens (out of line: keeps the evaluator's frames
/// small).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Fail {
    TooDeep(NodeId),
    ConstChan(u32, NodeId),
    BadChan(u32, NodeId),
    ConstVar(SlotId, NodeId),
    NoBrdf(SlotId, NodeId),
    FuncAsVar(SlotId, NodeId),
    UndefVar(SlotId, NodeId),
    FewArgs(SlotId, usize),
    UndefFunc(SlotId, NodeId),
    NotFunc(SlotId, NodeId),
    FewFuncArgs(SlotId, usize, NodeId),
    NotFuncName(SlotId, usize, NodeId),
    FewLibArgs(Lib, NodeId),
    ConstArg(NodeId),
    MissingArg(i64, usize, NodeId),
}

/// The message of a fatal error.
#[cold]
#[inline(never)]
pub(crate) fn describe(code: &Code, f: Fail) -> String {
    let at = |node: NodeId| match code.locs.get(node as usize) {
        Some(l) => code.place(*l),
        None => "a call from the renderer".to_string(),
    };
    let defined_at = |s: SlotId| code.place(code.slots[s as usize].def_loc);
    let name = |s: SlotId| code.name(s).to_string();
    match f {
        Fail::TooDeep(n) => format!(
            "recursion too deep (more than {MAX_DEPTH} nested evaluations or {} KB of \
                 stack) at {}",
            MAX_STACK >> 10,
            at(n)
        ),
        Fail::ConstChan(c, n) => format!(
            "ray parameter used in constant expression (${c} at {})",
            at(n)
        ),
        Fail::BadChan(c, n) => format!("illegal channel number ${c} at {}", at(n)),
        Fail::ConstVar(s, n) => format!(
            "ray parameter used in constant expression ({} at {})",
            name(s),
            at(n)
        ),
        Fail::NoBrdf(s, n) => format!(
            "{}: undefined variable (only BRDF materials define it; used at {})",
            name(s),
            at(n)
        ),
        Fail::FuncAsVar(s, n) => format!(
            "{}: function used as a variable at {} (defined at {})",
            name(s),
            at(n),
            defined_at(s)
        ),
        Fail::UndefVar(s, n) => {
            format!("{}: undefined variable (used at {})", name(s), at(n))
        }
        Fail::FewArgs(s, i) => format!(
            "{}(): too few arguments (parameter {} used; {} defined at {})",
            name(s),
            i + 1,
            name(s),
            defined_at(s)
        ),
        Fail::UndefFunc(s, n) => {
            format!("{}(): undefined function (called at {})", name(s), at(n))
        }
        Fail::NotFunc(s, n) => format!(
            "{}(): not a function (defined as a variable at {}, called at {})",
            name(s),
            defined_at(s),
            at(n)
        ),
        Fail::FewFuncArgs(s, i, n) => format!(
            "{}(): too few arguments (function parameter {} called at {})",
            name(s),
            i + 1,
            at(n)
        ),
        Fail::NotFuncName(s, i, n) => format!(
            "{}(): argument {} is not a function name (called at {})",
            name(s),
            i + 1,
            at(n)
        ),
        Fail::FewLibArgs(l, n) => {
            format!("{}(): too few arguments (called at {})", l.name(), at(n))
        }
        Fail::ConstArg(n) => format!(
            "arg() used in a constant expression at {} (a ':' definition that depends \
                 on the primitive's arguments?)",
            at(n)
        ),
        Fail::MissingArg(k, have, n) => format!(
            "missing real argument {k} (the primitive has {have}; arg() called at {})",
            at(n)
        ),
    }
}

impl<'a> Machine<'a> {
    #[cold]
    #[inline(never)]
    fn fail(&mut self, f: Fail) -> Trap {
        let msg = describe(self.code, f);
        if self.fatal.is_none() {
            self.fatal = Some(msg);
        }
        Trap::Fatal
    }

    /// Evaluate node `n` in frame `f`.
    pub fn eval(&mut self, n: NodeId, f: &Frame) -> R {
        self.depth += 1;
        if self.depth > MAX_DEPTH || self.stack.abs_diff(stack_here()) > MAX_STACK {
            return Err(self.fail(Fail::TooDeep(n)));
        }
        let r = match self.code.nodes[n as usize] {
            Node::Num(v) => Ok(v),
            Node::Chan(c) => match self.env {
                Some(env) if (1..=27).contains(&c) => Ok(env.chan[c as usize - 1]),
                Some(_) => Err(self.fail(Fail::BadChan(c, n))),
                None => Err(self.fail(Fail::ConstChan(c, n))),
            },
            Node::Var(s) => self.var(s, n),
            Node::Param(i) => {
                let i = i as usize;
                if i < NCACHE && f.done.get() >> i & 1 == 1 {
                    Ok(f.vals[i].get())
                } else {
                    self.param(f, i)
                }
            }
            Node::Neg(a) => self.eval(a, f).map(|v| -v),
            Node::Bin(op, a, b) => match self.operand(a, f) {
                Ok(x) => match self.operand(b, f) {
                    Ok(y) => binop(op, x, y),
                    Err(e) => Err(e),
                },
                Err(e) => Err(e),
            },
            Node::Call {
                callee,
                first,
                n: k,
            } => self.call(callee, first, k, f, n),
        };
        self.depth -= 1;
        r
    }

    /// An operand: numbers, channels and cached parameters without a call.
    #[inline(always)]
    fn operand(&mut self, n: NodeId, f: &Frame) -> R {
        match self.code.nodes[n as usize] {
            Node::Num(v) => Ok(v),
            Node::Chan(c @ 1..=27) if self.env.is_some() => {
                Ok(self.env.map_or(0.0, |e| e.chan[c as usize - 1]))
            }
            Node::Param(i) if (i as usize) < NCACHE && f.done.get() >> i & 1 == 1 => {
                Ok(f.vals[i as usize].get())
            }
            _ => self.eval(n, f),
        }
    }

    #[inline(never)]
    fn call(&mut self, callee: Callee, first: u32, k: u16, f: &Frame, n: NodeId) -> R {
        let list = self.code.args(first, k);
        let src = ArgSrc::Nodes { list, caller: f };
        match callee {
            Callee::Slot(s) => self.call_slot(s, src, n),
            Callee::Lib(l) => self.lib(l, src, n),
            Callee::Param(i) => self.call_param(f, i as usize, src, n),
        }
    }

    /// The value of variable slot `s`, referenced at node `site`.
    #[inline(never)]
    pub fn var(&mut self, s: SlotId, site: NodeId) -> R {
        match self.code.slots[s as usize].def {
            Def::Num(v) => Ok(v),
            Def::Var { expr, .. } => {
                if self.env.is_none() {
                    return self.eval(expr, &Frame::top());
                }
                let e = self.cache[s as usize];
                if e.tick == self.tick {
                    return Ok(e.value);
                }
                let v = self.eval(expr, &Frame::top())?;
                self.cache[s as usize] = Entry {
                    tick: self.tick,
                    value: v,
                };
                Ok(v)
            }
            Def::Brdf(i) => match self.env.map(|e| e.brdf) {
                None => Err(self.fail(Fail::ConstVar(s, site))),
                Some(Some(b)) => Ok(b[i as usize]),
                Some(None) => Err(self.fail(Fail::NoBrdf(s, site))),
            },
            Def::Func { .. } => Err(self.fail(Fail::FuncAsVar(s, site))),
            Def::None => Err(self.fail(Fail::UndefVar(s, site))),
        }
    }

    /// Parameter `i` of frame `f` (not cached yet): evaluated in the caller's frame.
    #[inline(never)]
    fn param(&mut self, f: &Frame, i: usize) -> R {
        param(self, f, i)
    }

    /// Call the definition of slot `s` (or its library fallback) at node `site`.
    pub fn call_slot(&mut self, s: SlotId, src: ArgSrc, site: NodeId) -> R {
        call_slot(self, s, src, site)
    }

    /// Call the function whose name the caller of frame `f` passed as parameter `i`.
    fn call_param(&mut self, f: &Frame, i: usize, src: ArgSrc, site: NodeId) -> R {
        call_param(self, f, i, src, site)
    }

    /// Call library function `l`.
    pub fn lib(&mut self, l: Lib, src: ArgSrc, site: NodeId) -> R {
        lib(self, l, &src, site)
    }
}

impl Host for Machine<'_> {
    fn code(&self) -> &Code {
        self.code
    }

    fn fail(&mut self, f: Fail) -> Trap {
        Machine::fail(self, f)
    }

    #[inline]
    fn eval_arg(&mut self, node: NodeId, caller: &Frame) -> R {
        self.operand(node, caller)
    }

    fn run_body(&mut self, _s: SlotId, body: NodeId, frame: &Frame) -> R {
        self.eval(body, frame)
    }

    fn real_args(&mut self, site: NodeId) -> Result<&[f64], Trap> {
        match self.env {
            Some(env) => Ok(env.args),
            None => Err(self.fail(Fail::ConstArg(site))),
        }
    }
}

/// What the evaluators (the tree walker and the run-time machine) differ in; the rules of
/// parameters, calls, function-name arguments and library calls by name are shared.
pub(crate) trait Host {
    fn code(&self) -> &Code;
    /// Record a fatal error.
    fn fail(&mut self, f: Fail) -> Trap;
    /// The value of argument expression `node` in its caller's frame.
    fn eval_arg(&mut self, node: NodeId, caller: &Frame) -> R;
    /// The body `body` of function `s`, in `frame`.
    fn run_body(&mut self, s: SlotId, body: NodeId, frame: &Frame) -> R;
    /// The primitive's real arguments (a fatal error in a constant expression).
    fn real_args(&mut self, site: NodeId) -> Result<&[f64], Trap>;
}

/// Parameter `i` of frame `f` (not cached yet): evaluated in the caller's frame, and
/// cached when it is one of the first [`NCACHE`].
pub(crate) fn param<H: Host>(h: &mut H, f: &Frame, i: usize) -> R {
    let v = match f.src {
        ArgSrc::Nodes { list, caller } if i < list.len() => h.eval_arg(list[i], caller)?,
        ArgSrc::Values(v) if i < v.len() => v[i],
        _ => return Err(h.fail(Fail::FewArgs(f.func, i))),
    };
    if i < NCACHE {
        f.vals[i].set(v);
        f.done.set(f.done.get() | 1 << i);
    }
    Ok(v)
}

/// Call the definition of slot `s` (or its library fallback) at node `site`.
pub(crate) fn call_slot<H: Host>(h: &mut H, s: SlotId, src: ArgSrc, site: NodeId) -> R {
    let slot = &h.code().slots[s as usize];
    match (slot.def, slot.lib) {
        (Def::Func { body, .. }, _) => {
            let frame = Frame::new(src, s);
            h.run_body(s, body, &frame)
        }
        (Def::None, Some(l)) => lib(h, l, &src, site),
        (Def::None, None) => Err(h.fail(Fail::UndefFunc(s, site))),
        _ => Err(h.fail(Fail::NotFunc(s, site))),
    }
}

/// Argument `i` of a call of library function `l` (a fatal error when missing).
#[inline]
fn lib_arg<H: Host>(h: &mut H, src: &ArgSrc, i: usize, l: Lib, site: NodeId) -> R {
    match *src {
        ArgSrc::Nodes { list, caller } if i < list.len() => h.eval_arg(list[i], caller),
        ArgSrc::Values(v) if i < v.len() => Ok(v[i]),
        _ => Err(h.fail(Fail::FewLibArgs(l, site))),
    }
}

/// Call the function whose name the caller of frame `f` passed as parameter `i` (the name
/// may be passed on through several calls).
pub(crate) fn call_param<H: Host>(h: &mut H, f: &Frame, i: usize, src: ArgSrc, site: NodeId) -> R {
    let mut frame = f;
    let mut i = i;
    loop {
        let (list, caller) = match frame.src {
            ArgSrc::Nodes { list, caller } if i < list.len() => (list, caller),
            _ => return Err(h.fail(Fail::FewFuncArgs(frame.func, i, site))),
        };
        match h.code().nodes[list[i] as usize] {
            Node::Var(s) => return call_slot(h, s, src, site),
            Node::Param(j) => {
                frame = caller;
                i = j as usize;
            }
            _ => return Err(h.fail(Fail::NotFuncName(frame.func, i, site))),
        }
    }
}

/// Call library function `l` with (lazy) arguments `src`.
pub(crate) fn lib<H: Host>(h: &mut H, l: Lib, src: &ArgSrc, site: NodeId) -> R {
    if let Some(f) = l.unary() {
        let x = lib_arg(h, src, 0, l, site)?;
        return check(f(x));
    }
    match l {
        Lib::If => {
            let c = lib_arg(h, src, 0, l, site)?;
            lib_arg(h, src, if c > 0.0 { 1 } else { 2 }, l, site)
        }
        _ => lib_other(h, l, src, site),
    }
}

#[inline(never)]
fn lib_other<H: Host>(h: &mut H, l: Lib, src: &ArgSrc, site: NodeId) -> R {
    match l {
        Lib::Select => {
            let d = lib_arg(h, src, 0, l, site)? + 0.5;
            let count = src.len().saturating_sub(1);
            match select_index(d, count)? {
                0 => Ok(count as f64),
                k => lib_arg(h, src, k, l, site),
            }
        }
        Lib::Min | Lib::Max => {
            // From the last argument backwards, as Radiance (a NaN last argument wins).
            let n = src.len();
            let mut best = lib_arg(h, src, n.max(1) - 1, l, site)?;
            for i in (0..n.saturating_sub(1)).rev() {
                let a = lib_arg(h, src, i, l, site)?;
                best = better(l == Lib::Max, best, a);
            }
            check(best)
        }
        Lib::Atan2 => {
            let y = lib_arg(h, src, 0, l, site)?;
            let x = lib_arg(h, src, 1, l, site)?;
            check(y.atan2(x))
        }
        Lib::Arg => {
            let x = lib_arg(h, src, 0, l, site)?;
            real_arg(h, x, site)
        }
        _ => {
            let x = lib_arg(h, src, 0, l, site)?;
            let y = lib_arg(h, src, 1, l, site)?;
            let z = lib_arg(h, src, 2, l, site)?;
            check(noise_fn(l, x, y, z))
        }
    }
}

/// `arg(x)`: the primitive's real argument `x` (rounded), or their count for `x < 1`.
pub(crate) fn real_arg<H: Host>(h: &mut H, x: f64, site: NodeId) -> R {
    let k = (x + 0.5) as i64;
    let args = h.real_args(site)?;
    let n = args.len();
    if k < 1 {
        return Ok(n as f64);
    }
    match args.get(k as usize - 1) {
        Some(v) => Ok(*v),
        None => Err(h.fail(Fail::MissingArg(k, n, site))),
    }
}

/// `select`'s argument number from `d` = first argument + 0.5: 0 asks for the count;
/// NaN, below 0 or past the count is a domain error.
#[inline]
pub(crate) fn select_index(d: f64, count: usize) -> Result<usize, Trap> {
    if d.is_nan() || d < 0.0 {
        return Err(Trap::Domain);
    }
    let k = d.trunc();
    if k > count as f64 {
        Err(Trap::Domain)
    } else {
        Ok(k as usize)
    }
}

/// `min`/`max`, taking the arguments from the last one backwards: `a` replaces `best`
/// only when strictly better.
#[inline]
pub(crate) fn better(max: bool, best: f64, a: f64) -> f64 {
    if (!max && a < best) || (max && a > best) {
        a
    } else {
        best
    }
}

#[inline(never)]
pub(crate) fn noise_fn(l: Lib, x: f64, y: f64, z: f64) -> f64 {
    match l {
        Lib::Noise3 => noise::noise3(x, y, z),
        Lib::Noise3x => noise::noise3_d(0, x, y, z),
        Lib::Noise3y => noise::noise3_d(1, x, y, z),
        Lib::Noise3z => noise::noise3_d(2, x, y, z),
        _ => noise::fnoise3(x, y, z),
    }
}

/// A binary operator with Radiance master's error rules.
pub(crate) fn binop(op: Op, x: f64, y: f64) -> R {
    match op {
        Op::Add => Ok(x + y),
        Op::Sub => Ok(x - y),
        Op::Mul => Ok(x * y),
        Op::Div => {
            if y == 0.0 {
                Err(Trap::Range)
            } else {
                Ok(x / y)
            }
        }
        Op::Pow => check(x.powf(y)),
    }
}
