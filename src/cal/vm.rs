//! The run-time evaluator of a finished [`super::Program`]: the blocks of stack code that
//! [`super::compile`] made, run in a loop. A variable not yet computed in this evaluation
//! runs its block in the same loop (its return place on the value stack); only a
//! function call and an argument evaluated lazily in its caller's frame recurse.
//!
//! The semantics are the tree walker's ([`super::eval::Machine`], which folds constants
//! while compiling): the same lazy, per-call cached arguments, per-evaluation cached
//! variables, error rules and messages, and the same order of evaluation. The recursion
//! limit counts nested blocks (each a variable, call or argument evaluation), not nodes.

use super::code::{Code, NodeId, Op, SlotId};
use super::compile::{Compiled, Ins, Rhs, NONE};
use super::eval::{
    better, binop, call_param, check, describe, noise_fn, param, real_arg, select_index,
    stack_here, ArgSrc, Entry, Fail, Frame, Host, Trap, MAX_DEPTH, MAX_STACK, NCACHE, R,
};
use super::Env;

/// One evaluation's machine.
pub(crate) struct Vm<'a> {
    pub prog: &'a Compiled,
    pub code: &'a Code,
    pub env: &'a Env<'a>,
    pub cache: &'a mut [Entry],
    pub stack: &'a mut Vec<f64>,
    /// The frame variables are evaluated in (no arguments).
    pub top: &'a Frame<'a>,
    pub tick: u64,
    pub depth: u32,
    /// [`stack_here`] where the evaluation started.
    pub origin: usize,
    pub fatal: Option<String>,
}

impl Vm<'_> {
    #[cold]
    #[inline(never)]
    fn fail(&mut self, f: Fail) -> Trap {
        if self.fatal.is_none() {
            self.fatal = Some(describe(self.code, f));
        }
        Trap::Fatal
    }

    /// The recursion limit's error for a block starting at `pc`.
    #[cold]
    #[inline(never)]
    fn too_deep(&mut self, pc: u32) -> Trap {
        let site = self.prog.site.get(pc as usize).copied().unwrap_or(NONE);
        self.fail(Fail::TooDeep(site))
    }

    /// Run the block at `pc` in frame `f`.
    pub fn run(&mut self, pc: u32, f: &Frame) -> R {
        self.depth += 1;
        if self.depth > MAX_DEPTH || self.origin.abs_diff(stack_here()) > MAX_STACK {
            return Err(self.too_deep(pc));
        }
        let (base, depth) = (self.stack.len(), self.depth);
        let r = self.exec(pc as usize, f);
        self.stack.truncate(base);
        // Variables whose blocks ran inline in `exec` counted too; an error leaves them.
        self.depth = depth - 1;
        r
    }

    #[inline(always)]
    fn pop(&mut self) -> f64 {
        self.stack.pop().unwrap_or(0.0)
    }

    /// Variable `slot` (block `block`): cached in this evaluation, or computed now.
    #[inline(always)]
    fn var(&mut self, slot: SlotId, block: u32) -> R {
        let e = self.cache[slot as usize];
        if e.tick == self.tick {
            return Ok(e.value);
        }
        let v = self.run(block, self.top)?;
        self.cache[slot as usize] = Entry {
            tick: self.tick,
            value: v,
        };
        Ok(v)
    }

    /// Parameter `i` of frame `f`.
    #[inline(always)]
    fn param_of(&mut self, f: &Frame, i: u16) -> R {
        let i = i as usize;
        if i < NCACHE && f.done.get() >> i & 1 == 1 {
            Ok(f.vals[i].get())
        } else {
            param(self, f, i)
        }
    }

    /// The block at `pc` in frame `f`. A variable not computed yet in this evaluation has
    /// its block run in this same loop (no recursion): its return place and slot go on the
    /// value stack, its code runs in the variables' frame, and its `Ret` caches the value
    /// and comes back. Each such block counts as a nested block against [`MAX_DEPTH`], as
    /// one run by [`Vm::run`] does.
    fn exec(&mut self, mut pc: usize, f0: &Frame) -> R {
        let prog = self.prog;
        let top = self.top;
        let mut f = f0;
        let mut nested = 0u32;
        let mut acc = 0.0;
        loop {
            match prog.ins[pc] {
                Ins::Num(v) => acc = v,
                Ins::Chan(c) => acc = self.env.chan[c as usize],
                Ins::Var { slot, block } => {
                    let e = self.cache[slot as usize];
                    if e.tick == self.tick {
                        acc = e.value;
                    } else {
                        self.depth += 1;
                        if self.depth > MAX_DEPTH {
                            return Err(self.too_deep(block));
                        }
                        self.stack
                            .push(f64::from_bits((pc as u64) << 32 | u64::from(slot)));
                        nested += 1;
                        f = top;
                        pc = block as usize;
                        continue;
                    }
                }
                Ins::Brdf { i, slot, site } => match self.env.brdf {
                    Some(b) => acc = b[i as usize],
                    None => return Err(self.fail(Fail::NoBrdf(slot, site))),
                },
                Ins::Param(i) => acc = self.param_of(f, i)?,
                Ins::Push => self.stack.push(acc),
                Ins::Neg => acc = -acc,
                Ins::Bin(op, rhs) => {
                    acc = match rhs {
                        Rhs::Acc => {
                            let a = self.pop();
                            apply(op, a, acc)?
                        }
                        Rhs::Num(v) => apply(op, acc, v)?,
                        Rhs::Chan(c) => apply(op, acc, self.env.chan[c as usize])?,
                        Rhs::Param(i) => {
                            let b = self.param_of(f, i)?;
                            apply(op, acc, b)?
                        }
                        Rhs::Var { slot, block } => {
                            let b = self.var(slot, block)?;
                            apply(op, acc, b)?
                        }
                    }
                }
                Ins::NumBin(op, v) => acc = apply(op, v, acc)?,
                Ins::ChanBin(op, c) => acc = apply(op, self.env.chan[c as usize], acc)?,
                Ins::Unary(g) => acc = check(g(acc))?,
                Ins::Atan2 => {
                    let y = self.pop();
                    acc = check(y.atan2(acc))?;
                }
                Ins::Noise(l) => {
                    let y = self.pop();
                    let x = self.pop();
                    acc = check(noise_fn(l, x, y, acc))?;
                }
                Ins::MinMax { max, n } => {
                    // n - 1 values pushed, the first argument in the accumulator.
                    self.stack.push(acc);
                    let at = self.stack.len() - n as usize;
                    let best = min_max(max, &self.stack[at..]);
                    self.stack.truncate(at);
                    acc = check(best)?;
                }
                Ins::ArgFn(site) => acc = real_arg(self, acc, site)?,
                Ins::JumpUnlessPos(t) => {
                    // NaN is not positive.
                    if acc.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                        pc = t as usize;
                        continue;
                    }
                }
                Ins::Jump(t) => {
                    pc = t as usize;
                    continue;
                }
                Ins::Select { count, at } => {
                    let k = select_index(acc + 0.5, count as usize)?;
                    if k == 0 {
                        acc = count as f64;
                    }
                    pc = prog.table[at as usize + k] as usize;
                    continue;
                }
                Ins::Call {
                    body,
                    func,
                    first,
                    n,
                } => {
                    let list = self.code.args(first, n);
                    let frame = Frame::new(ArgSrc::Nodes { list, caller: f }, func);
                    acc = self.run(body, &frame)?;
                }
                Ins::CallParam { i, first, n, site } => {
                    let list = self.code.args(first, n);
                    let src = ArgSrc::Nodes { list, caller: f };
                    acc = call_param(self, f, i as usize, src, site)?;
                }
                Ins::Fail(k) => return Err(self.fail(prog.fails[k as usize])),
                Ins::Ret => {
                    if nested == 0 {
                        return Ok(acc);
                    }
                    // The end of a variable's block: cache its value, go back.
                    let rec = self.stack.pop().unwrap_or(0.0).to_bits();
                    nested -= 1;
                    self.depth -= 1;
                    self.cache[(rec & 0xFFFF_FFFF) as usize] = Entry {
                        tick: self.tick,
                        value: acc,
                    };
                    pc = (rec >> 32) as usize;
                    if nested == 0 {
                        f = f0;
                    }
                }
            }
            pc += 1;
        }
    }
}

impl Host for Vm<'_> {
    fn code(&self) -> &Code {
        self.code
    }

    fn fail(&mut self, f: Fail) -> Trap {
        Vm::fail(self, f)
    }

    /// An argument's own block, run in its caller's frame.
    fn eval_arg(&mut self, node: NodeId, caller: &Frame) -> R {
        let b = self.prog.block_of[node as usize];
        self.run(b, caller)
    }

    fn run_body(&mut self, s: SlotId, _body: NodeId, frame: &Frame) -> R {
        self.run(self.prog.slot_block[s as usize], frame)
    }

    fn real_args(&mut self, _site: NodeId) -> Result<&[f64], Trap> {
        Ok(self.env.args)
    }
}

/// `min`/`max` of values listed from the last argument to the first.
fn min_max(max: bool, from_last: &[f64]) -> f64 {
    let mut it = from_last.iter().copied();
    let first = it.next().unwrap_or(0.0);
    it.fold(first, |best, a| better(max, best, a))
}

/// A binary operator (the tree walker's rules).
#[inline(always)]
fn apply(op: Op, x: f64, y: f64) -> R {
    match op {
        Op::Add => Ok(x + y),
        Op::Sub => Ok(x - y),
        Op::Mul => Ok(x * y),
        _ => binop(op, x, y),
    }
}
