//! The evaluator: a recursive walk over the node arena with lazy, per-call cached
//! arguments, per-evaluation cached variables and a depth limit.
//!
//! Errors travel as a small [`Trap`]; a fatal error's message is kept in the machine
//! until the public API turns it into [`super::EvalError::Fatal`].

use super::code::{Callee, Code, Def, Node, NodeId, Op, SlotId};
use super::library::Lib;
use super::noise;
use super::Env;
use std::cell::Cell;

/// The deepest nesting of node evaluations (expression depth plus function and variable
/// calls, added up) one evaluation may reach. It keeps the evaluator's stack use under
/// about 1 MB in a debug build (far less in a release build), so a runaway recursion is a
/// fatal error, never a stack overflow, even on a 2 MB thread.
pub const MAX_DEPTH: u32 = 4000;

/// Arguments cached per call (Radiance caches the first 10; later ones are re-evaluated on
/// each use, which is equivalent since evaluation has no side effects).
const NCACHE: usize = 12;

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
    fn len(&self) -> usize {
        match self {
            ArgSrc::None => 0,
            ArgSrc::Nodes { list, .. } => list.len(),
            ArgSrc::Values(v) => v.len(),
        }
    }
}

/// One function call's frame.
pub(crate) struct Frame<'f> {
    src: ArgSrc<'f>,
    /// The function called (for messages); u32::MAX at top level.
    func: SlotId,
    done: Cell<u32>,
    vals: [Cell<f64>; NCACHE],
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
    pub fatal: Option<String>,
}

fn check(v: f64) -> R {
    if v.is_nan() {
        Err(Trap::Domain)
    } else if v.is_infinite() {
        Err(Trap::Range)
    } else {
        Ok(v)
    }
}

impl<'a> Machine<'a> {
    fn fail(&mut self, msg: String) -> Trap {
        if self.fatal.is_none() {
            self.fatal = Some(msg);
        }
        Trap::Fatal
    }

    fn at(&self, node: NodeId) -> String {
        match self.code.locs.get(node as usize) {
            Some(l) => self.code.place(*l),
            None => "a call from the renderer".to_string(),
        }
    }

    fn defined_at(&self, s: SlotId) -> String {
        self.code.place(self.code.slots[s as usize].def_loc)
    }

    /// Evaluate node `n` in frame `f`.
    pub fn eval(&mut self, n: NodeId, f: &Frame) -> R {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let msg = format!(
                "recursion too deep (more than {MAX_DEPTH} nested evaluations) at {}",
                self.at(n)
            );
            return Err(self.fail(msg));
        }
        let r = match self.code.nodes[n as usize] {
            Node::Num(v) => Ok(v),
            Node::Chan(c) => self.chan(c, n),
            Node::Var(s) => self.var(s, n),
            Node::Param(i) => self.param(f, i as usize),
            Node::Neg(a) => self.eval(a, f).map(|v| -v),
            Node::Bin(op, a, b) => {
                let x = self.eval(a, f)?;
                let y = self.eval(b, f)?;
                binop(op, x, y)
            }
            Node::Call { callee, first, n: k } => {
                let list = self.code.args(first, k);
                let src = ArgSrc::Nodes { list, caller: f };
                match callee {
                    Callee::Slot(s) => self.call_slot(s, src, n),
                    Callee::Lib(l) => self.lib(l, src, n),
                    Callee::Param(i) => self.call_param(f, i as usize, src, n),
                }
            }
        };
        self.depth -= 1;
        r
    }

    fn chan(&mut self, c: u32, n: NodeId) -> R {
        match self.env {
            None => Err(self.fail(format!(
                "ray parameter used in constant expression (${} at {})",
                c,
                self.at(n)
            ))),
            Some(env) => match env.chan.get((c as usize).wrapping_sub(1)) {
                Some(v) => Ok(*v),
                None => Err(self.fail(format!(
                    "illegal channel number ${} at {}",
                    c,
                    self.at(n)
                ))),
            },
        }
    }

    /// The value of variable slot `s`, referenced at node `site`.
    pub fn var(&mut self, s: SlotId, site: NodeId) -> R {
        let slot = &self.code.slots[s as usize];
        match slot.def {
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
            Def::Brdf(i) => match self.env {
                None => Err(self.fail(format!(
                    "ray parameter used in constant expression ({} at {})",
                    slot.name,
                    self.at(site)
                ))),
                Some(env) => match env.brdf {
                    Some(b) => Ok(b[i as usize]),
                    None => Err(self.fail(format!(
                        "{}: undefined variable (only BRDF materials define it; used at {})",
                        slot.name,
                        self.at(site)
                    ))),
                },
            },
            Def::Func { .. } => Err(self.fail(format!(
                "{}: function used as a variable at {} (defined at {})",
                slot.name,
                self.at(site),
                self.defined_at(s)
            ))),
            Def::None => Err(self.fail(format!(
                "{}: undefined variable (used at {})",
                slot.name,
                self.at(site)
            ))),
        }
    }

    /// Parameter `i` of frame `f`: cached, or evaluated in the caller's frame.
    fn param(&mut self, f: &Frame, i: usize) -> R {
        if i < NCACHE && f.done.get() >> i & 1 == 1 {
            return Ok(f.vals[i].get());
        }
        let v = match f.src {
            ArgSrc::Nodes { list, caller } if i < list.len() => self.eval(list[i], caller)?,
            ArgSrc::Values(v) if i < v.len() => v[i],
            _ => {
                let name = self.code.name(f.func).to_string();
                let def = self.defined_at(f.func);
                return Err(self.fail(format!(
                    "{name}(): too few arguments (parameter {} used; {name} defined at {def})",
                    i + 1
                )));
            }
        };
        if i < NCACHE {
            f.vals[i].set(v);
            f.done.set(f.done.get() | 1 << i);
        }
        Ok(v)
    }

    /// Call the definition of slot `s` (or its library fallback) at node `site`.
    pub fn call_slot(&mut self, s: SlotId, src: ArgSrc, site: NodeId) -> R {
        let slot = &self.code.slots[s as usize];
        match slot.def {
            Def::Func { body, .. } => {
                let frame = Frame::new(src, s);
                self.eval(body, &frame)
            }
            Def::None => match slot.lib {
                Some(l) => self.lib(l, src, site),
                None => Err(self.fail(format!(
                    "{}(): undefined function (called at {})",
                    slot.name,
                    self.at(site)
                ))),
            },
            _ => Err(self.fail(format!(
                "{}(): not a function (defined as a variable at {}, called at {})",
                slot.name,
                self.defined_at(s),
                self.at(site)
            ))),
        }
    }

    /// Call the function whose name the caller of frame `f` passed as parameter `i`.
    fn call_param(&mut self, f: &Frame, i: usize, src: ArgSrc, site: NodeId) -> R {
        let mut frame = f;
        let mut i = i;
        loop {
            let (list, caller) = match frame.src {
                ArgSrc::Nodes { list, caller } if i < list.len() => (list, caller),
                _ => {
                    let name = self.code.name(frame.func).to_string();
                    return Err(self.fail(format!(
                        "{name}(): too few arguments (function parameter {} called at {})",
                        i + 1,
                        self.at(site)
                    )));
                }
            };
            match self.code.nodes[list[i] as usize] {
                Node::Var(s) => return self.call_slot(s, src, site),
                Node::Param(j) => {
                    frame = caller;
                    i = j as usize;
                }
                _ => {
                    let name = self.code.name(frame.func).to_string();
                    return Err(self.fail(format!(
                        "{name}(): argument {} is not a function name (called at {})",
                        i + 1,
                        self.at(site)
                    )));
                }
            }
        }
    }

    /// Argument `i` of a library call.
    fn arg(&mut self, src: &ArgSrc, i: usize, l: Lib, site: NodeId) -> R {
        match *src {
            ArgSrc::Nodes { list, caller } if i < list.len() => self.eval(list[i], caller),
            ArgSrc::Values(v) if i < v.len() => Ok(v[i]),
            _ => Err(self.fail(format!(
                "{}(): too few arguments (called at {})",
                l.name(),
                self.at(site)
            ))),
        }
    }

    /// Call library function `l`.
    pub fn lib(&mut self, l: Lib, src: ArgSrc, site: NodeId) -> R {
        if let Some(f) = l.unary() {
            let x = self.arg(&src, 0, l, site)?;
            return check(f(x));
        }
        match l {
            Lib::If => {
                let c = self.arg(&src, 0, l, site)?;
                self.arg(&src, if c > 0.0 { 1 } else { 2 }, l, site)
            }
            Lib::Select => {
                let d = self.arg(&src, 0, l, site)? + 0.5;
                if !(d >= 0.0) {
                    return Err(Trap::Domain);
                }
                let count = src.len().saturating_sub(1);
                let k = d.trunc();
                if k == 0.0 {
                    Ok(count as f64)
                } else if k > count as f64 {
                    Err(Trap::Domain)
                } else {
                    self.arg(&src, k as usize, l, site)
                }
            }
            Lib::Min | Lib::Max => {
                // From the last argument backwards, as Radiance (a NaN last argument wins).
                let n = src.len();
                let mut best = self.arg(&src, n.max(1) - 1, l, site)?;
                for i in (0..n.saturating_sub(1)).rev() {
                    let a = self.arg(&src, i, l, site)?;
                    if (l == Lib::Min && a < best) || (l == Lib::Max && a > best) {
                        best = a;
                    }
                }
                check(best)
            }
            Lib::Atan2 => {
                let y = self.arg(&src, 0, l, site)?;
                let x = self.arg(&src, 1, l, site)?;
                check(y.atan2(x))
            }
            Lib::Arg => self.arg_fn(&src, site),
            Lib::Noise3 | Lib::Noise3x | Lib::Noise3y | Lib::Noise3z | Lib::Fnoise3 => {
                let x = self.arg(&src, 0, l, site)?;
                let y = self.arg(&src, 1, l, site)?;
                let z = self.arg(&src, 2, l, site)?;
                check(match l {
                    Lib::Noise3 => noise::noise3(x, y, z),
                    Lib::Noise3x => noise::noise3_d(0, x, y, z),
                    Lib::Noise3y => noise::noise3_d(1, x, y, z),
                    Lib::Noise3z => noise::noise3_d(2, x, y, z),
                    _ => noise::fnoise3(x, y, z),
                })
            }
            _ => unreachable!("unary library function {l:?} handled above"),
        }
    }

    /// `arg(n)`: the primitive's real arguments.
    fn arg_fn(&mut self, src: &ArgSrc, site: NodeId) -> R {
        let x = self.arg(src, 0, Lib::Arg, site)?;
        let Some(env) = self.env else {
            return Err(self.fail(format!(
                "arg() used in a constant expression at {} (a ':' definition that \
                 depends on the primitive's arguments?)",
                self.at(site)
            )));
        };
        let k = (x + 0.5) as i64;
        if k < 1 {
            return Ok(env.args.len() as f64);
        }
        match env.args.get(k as usize - 1) {
            Some(v) => Ok(*v),
            None => Err(self.fail(format!(
                "missing real argument {k} (the primitive has {}; arg() called at {})",
                env.args.len(),
                self.at(site)
            ))),
        }
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
