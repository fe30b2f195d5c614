//! The compiler of a finished [`super::Program`] for the run-time machine
//! ([`super::vm`]): every variable definition, function body, top-level expression and
//! call argument becomes a block of stack code (jumps for `if` and `select`). Small
//! functions called with short arguments are compiled inline ([`Compiler::can_inline`]).

use super::code::{Callee, Code, Def, Node, NodeId, Op, SlotId};
use super::eval::Fail;
use super::library::Lib;

/// "No block" in [`Compiled::block_of`] and in jump fix-ups.
pub(super) const NONE: u32 = u32::MAX;

/// Where the right operand of a binary operator comes from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Rhs {
    /// The accumulator (the left operand was pushed).
    Acc,
    Num(f64),
    Chan(u8),
    Param(u16),
    Var {
        slot: SlotId,
        block: u32,
    },
}

/// One instruction. A block computes its value in an accumulator; a value waiting for the
/// other operand of an operator or for more arguments is pushed on the evaluation's stack.
#[derive(Debug, Clone, Copy)]
pub(super) enum Ins {
    Num(f64),
    /// Ray channel (0-based).
    Chan(u8),
    /// A variable defined by an expression: its cached value, or its block run now.
    Var {
        slot: SlotId,
        block: u32,
    },
    /// One of the BRDF variables.
    Brdf {
        i: u8,
        slot: SlotId,
        site: NodeId,
    },
    /// Parameter `i` of the current frame.
    Param(u16),
    /// Push the accumulator.
    Push,
    Neg,
    /// `acc = left op right`: with [`Rhs::Acc`] the left operand is popped and the right
    /// one is the accumulator; otherwise the accumulator is the left operand.
    Bin(Op, Rhs),
    /// `acc = v op acc` (a number on the left of an operand that is not a leaf).
    NumBin(Op, f64),
    /// `acc = chan op acc`.
    ChanBin(Op, u8),
    Unary(fn(f64) -> f64),
    /// `atan2(pop, acc)`.
    Atan2,
    /// `noise(pop, pop, acc)` (x was pushed first).
    Noise(Lib),
    /// `min`/`max` of `n - 1` pushed values and the accumulator (from the last argument
    /// to the first).
    MinMax {
        max: bool,
        n: u16,
    },
    /// `arg(acc)`.
    ArgFn(NodeId),
    /// Jump unless the accumulator is positive (`if`).
    JumpUnlessPos(u32),
    Jump(u32),
    /// `select`'s rule on the accumulator; the targets are `table[at..=at+count]` (`at`
    /// is the end, for `select(0, …)`, which leaves the count in the accumulator).
    Select {
        count: u16,
        at: u32,
    },
    /// Call function `func` (body block `body`) with the arguments `code.args(first, n)`.
    Call {
        body: u32,
        func: SlotId,
        first: u32,
        n: u16,
    },
    /// Call the function the caller passed as parameter `i`.
    CallParam {
        i: u16,
        first: u32,
        n: u16,
        site: NodeId,
    },
    /// A fatal error ([`Compiled::fails`]).
    Fail(u32),
    /// The block's value is the accumulator.
    Ret,
}

/// The compiled blocks of a program.
#[derive(Debug, Default)]
pub(crate) struct Compiled {
    pub(super) ins: Vec<Ins>,
    /// The node each instruction came from (for messages).
    pub(super) site: Vec<NodeId>,
    /// Jump tables of `select`.
    pub(super) table: Vec<u32>,
    pub(super) fails: Vec<Fail>,
    /// The block of each node compiled as a call argument (NONE otherwise).
    pub(super) block_of: Vec<u32>,
    /// The block of each slot's definition (a variable's expression, a function's body).
    pub(super) slot_block: Vec<u32>,
}

struct Compiler<'c> {
    code: &'c Code,
    out: Compiled,
    /// Argument nodes waiting for their own block.
    pending: Vec<NodeId>,
    /// Instructions whose block field is a slot waiting for its block.
    fixups: Vec<usize>,
    /// Slots whose definition must be compiled.
    wanted: Vec<SlotId>,
    /// Calls being compiled inline, innermost last: each call's argument list. A
    /// parameter met in an inlined body is its argument, compiled in the context of the
    /// call ([`Compiler::can_inline`]).
    inline: Vec<(u32, u16)>,
    /// How many of `inline` apply to the node being compiled (fewer while an argument is
    /// compiled in its caller's context).
    visible: usize,
}

/// Deepest nesting of inlined calls.
const INLINE_DEPTH: u32 = 4;
/// Most nodes an inlined body (with what it inlines) may have.
const INLINE_NODES: u32 = 64;
/// Most nodes of an argument that an inlined body may repeat at each of its uses.
const ARG_NODES: u32 = 3;

impl Compiled {
    /// Call instructions in the block starting at `pc` (up to its `Ret`).
    #[cfg(test)]
    pub(crate) fn calls_in(&self, pc: u32) -> usize {
        self.ins[pc as usize..]
            .iter()
            .take_while(|i| !matches!(i, Ins::Ret))
            .filter(|i| matches!(i, Ins::Call { .. } | Ins::CallParam { .. }))
            .count()
    }

    /// Compile every definition and every expression of `code`; returns the blocks of
    /// `exprs` in order.
    pub fn new(code: &Code, exprs: &[NodeId]) -> (Compiled, Vec<u32>) {
        let mut c = Compiler {
            code,
            out: Compiled {
                block_of: vec![NONE; code.nodes.len()],
                slot_block: vec![NONE; code.slots.len()],
                ..Compiled::default()
            },
            pending: Vec::new(),
            fixups: Vec::new(),
            wanted: (0..code.slots.len() as u32).collect(),
            inline: Vec::new(),
            visible: 0,
        };
        let blocks = exprs.iter().map(|&e| c.block(e)).collect();
        loop {
            if let Some(n) = c.pending.pop() {
                if c.out.block_of[n as usize] == NONE {
                    let b = c.block(n);
                    c.out.block_of[n as usize] = b;
                }
            } else if let Some(s) = c.wanted.pop() {
                if c.out.slot_block[s as usize] == NONE {
                    let body = match code.slots[s as usize].def {
                        Def::Var { expr, .. } => Some(expr),
                        Def::Func { body, .. } => Some(body),
                        _ => None,
                    };
                    if let Some(e) = body {
                        let b = c.block(e);
                        c.out.slot_block[s as usize] = b;
                    }
                }
            } else {
                break;
            }
        }
        for pc in std::mem::take(&mut c.fixups) {
            match &mut c.out.ins[pc] {
                Ins::Var { slot, block } => *block = c.out.slot_block[*slot as usize],
                Ins::Call { body, func, .. } => *body = c.out.slot_block[*func as usize],
                Ins::Bin(_, Rhs::Var { slot, block }) => *block = c.out.slot_block[*slot as usize],
                _ => {}
            }
        }
        (c.out, blocks)
    }
}

impl Compiler<'_> {
    fn emit(&mut self, i: Ins, site: NodeId) -> usize {
        self.out.ins.push(i);
        self.out.site.push(site);
        self.out.ins.len() - 1
    }

    fn fail(&mut self, f: Fail, site: NodeId) {
        self.out.fails.push(f);
        let k = self.out.fails.len() as u32 - 1;
        self.emit(Ins::Fail(k), site);
    }

    fn here(&self) -> u32 {
        self.out.ins.len() as u32
    }

    /// A block computing node `n` (ends with `Ret`).
    fn block(&mut self, n: NodeId) -> u32 {
        let start = self.here();
        self.node(n);
        self.emit(Ins::Ret, n);
        start
    }

    /// Code leaving the value of node `n` in the accumulator.
    fn node(&mut self, n: NodeId) {
        match self.code.nodes[n as usize] {
            Node::Num(v) => {
                self.emit(Ins::Num(v), n);
            }
            Node::Chan(c) => {
                if (1..=27).contains(&c) {
                    self.emit(Ins::Chan(c as u8 - 1), n);
                } else {
                    self.fail(Fail::BadChan(c, n), n);
                }
            }
            Node::Var(s) => match self.code.slots[s as usize].def {
                Def::Num(v) => {
                    self.emit(Ins::Num(v), n);
                }
                Def::Var { .. } => {
                    let pc = self.emit(
                        Ins::Var {
                            slot: s,
                            block: NONE,
                        },
                        n,
                    );
                    self.fixups.push(pc);
                }
                Def::Brdf(i) => {
                    self.emit(
                        Ins::Brdf {
                            i,
                            slot: s,
                            site: n,
                        },
                        n,
                    );
                }
                Def::Func { .. } => self.fail(Fail::FuncAsVar(s, n), n),
                Def::None => self.fail(Fail::UndefVar(s, n), n),
            },
            Node::Param(i) => match self.inlined_arg(i) {
                Some(a) => {
                    self.visible -= 1;
                    self.node(a);
                    self.visible += 1;
                }
                None => {
                    self.emit(Ins::Param(i), n);
                }
            },
            Node::Neg(a) => {
                self.node(a);
                self.emit(Ins::Neg, n);
            }
            Node::Bin(op, a, b) => {
                if let Some(rhs) = self.leaf(b) {
                    self.node(a);
                    let pc = self.emit(Ins::Bin(op, rhs), n);
                    if let Rhs::Var { .. } = rhs {
                        self.fixups.push(pc);
                    }
                    return;
                }
                // A left operand that cannot fail may be read after the right one.
                match self.leaf(a) {
                    Some(Rhs::Num(v)) => {
                        self.node(b);
                        self.emit(Ins::NumBin(op, v), n);
                    }
                    Some(Rhs::Chan(c)) => {
                        self.node(b);
                        self.emit(Ins::ChanBin(op, c), n);
                    }
                    _ => {
                        self.node(a);
                        self.emit(Ins::Push, n);
                        self.node(b);
                        self.emit(Ins::Bin(op, Rhs::Acc), n);
                    }
                }
            }
            Node::Call {
                callee,
                first,
                n: k,
            } => self.call(callee, first, k, n),
        }
    }

    /// The argument that parameter `i` stands for in the innermost visible inlined call.
    fn inlined_arg(&self, i: u16) -> Option<NodeId> {
        let (first, k) = *self.inline[..self.visible].last()?;
        self.code.args(first, k).get(i as usize).copied()
    }

    /// Node `n` as an operand read directly, when it is a leaf.
    fn leaf(&self, n: NodeId) -> Option<Rhs> {
        self.leaf_in(n, self.visible)
    }

    /// [`Compiler::leaf`] with `visible` inlined calls applying.
    fn leaf_in(&self, n: NodeId, visible: usize) -> Option<Rhs> {
        match self.code.nodes[n as usize] {
            Node::Num(v) => Some(Rhs::Num(v)),
            Node::Chan(c @ 1..=27) => Some(Rhs::Chan(c as u8 - 1)),
            Node::Param(i) if visible > 0 => {
                let (first, k) = self.inline[visible - 1];
                let a = *self.code.args(first, k).get(i as usize)?;
                self.leaf_in(a, visible - 1)
            }
            Node::Param(i) => Some(Rhs::Param(i)),
            Node::Var(s) => match self.code.slots[s as usize].def {
                Def::Num(v) => Some(Rhs::Num(v)),
                Def::Var { .. } => Some(Rhs::Var {
                    slot: s,
                    block: NONE,
                }),
                _ => None,
            },
            _ => None,
        }
    }

    fn call(&mut self, callee: Callee, first: u32, k: u16, site: NodeId) {
        match callee {
            Callee::Slot(s) => {
                let slot = &self.code.slots[s as usize];
                match slot.def {
                    Def::Func { body, .. } if self.can_inline(s, first, k, 0, &mut 0) => {
                        self.inline.push((first, k));
                        self.visible += 1;
                        self.node(body);
                        self.visible -= 1;
                        self.inline.pop();
                    }
                    Def::Func { .. } => {
                        debug_assert_eq!(self.visible, 0, "a call in an inlined body");
                        self.args_later(first, k);
                        let pc = self.emit(
                            Ins::Call {
                                body: NONE,
                                func: s,
                                first,
                                n: k,
                            },
                            site,
                        );
                        self.fixups.push(pc);
                    }
                    Def::None => match slot.lib {
                        Some(l) => self.lib(l, first, k, site),
                        None => self.fail(Fail::UndefFunc(s, site), site),
                    },
                    _ => self.fail(Fail::NotFunc(s, site), site),
                }
            }
            Callee::Lib(l) => self.lib(l, first, k, site),
            Callee::Param(i) => {
                self.args_later(first, k);
                self.emit(
                    Ins::CallParam {
                        i,
                        first,
                        n: k,
                        site,
                    },
                    site,
                );
            }
        }
    }

    /// Whether the call of function `s` with the arguments `code.args(first, k)` may be
    /// compiled inline, `depth` inlined calls deep, `nodes` counting the nodes inlined so
    /// far. The code is then the same operations in the same order as the call's, so every
    /// value and error stays as it was: the call passes exactly the function's parameters,
    /// each argument is a short expression without calls (a number, channel, variable or
    /// parameter, or a negation or `+ - * /` of such), which the body computes where it
    /// uses the parameter (the call would compute it there once and keep it: the same
    /// value, and the same error at the same first use); the body has no call of a
    /// function passed as a parameter, no call of its own that cannot be inlined too,
    /// and nothing that compiles to a fatal error.
    fn can_inline(&self, s: SlotId, first: u32, k: u16, depth: u32, nodes: &mut u32) -> bool {
        let Def::Func { nparams, body, .. } = self.code.slots[s as usize].def else {
            return false;
        };
        depth < INLINE_DEPTH
            && nparams == k
            && self
                .code
                .args(first, k)
                .iter()
                .all(|&a| self.simple_arg(a, &mut 0))
            && self.inline_body(body, k, depth, nodes)
    }

    /// Whether `n` is a call-free argument of at most [`ARG_NODES`] nodes.
    fn simple_arg(&self, n: NodeId, count: &mut u32) -> bool {
        *count += 1;
        if *count > ARG_NODES {
            return false;
        }
        match self.code.nodes[n as usize] {
            Node::Num(_) | Node::Param(_) | Node::Chan(1..=27) => true,
            Node::Var(v) => matches!(
                self.code.slots[v as usize].def,
                Def::Num(_) | Def::Var { .. }
            ),
            Node::Neg(a) => self.simple_arg(a, count),
            Node::Bin(Op::Add | Op::Sub | Op::Mul | Op::Div, a, b) => {
                self.simple_arg(a, count) && self.simple_arg(b, count)
            }
            _ => false,
        }
    }

    /// Whether the body node `n` compiles inline ([`Compiler::can_inline`]).
    fn inline_body(&self, n: NodeId, k: u16, depth: u32, nodes: &mut u32) -> bool {
        *nodes += 1;
        if *nodes > INLINE_NODES {
            return false;
        }
        match self.code.nodes[n as usize] {
            Node::Num(_) | Node::Chan(1..=27) => true,
            Node::Param(i) => i < k,
            Node::Chan(_) => false,
            Node::Var(v) => matches!(
                self.code.slots[v as usize].def,
                Def::Num(_) | Def::Var { .. }
            ),
            Node::Neg(a) => self.inline_body(a, k, depth, nodes),
            Node::Bin(_, a, b) => {
                self.inline_body(a, k, depth, nodes) && self.inline_body(b, k, depth, nodes)
            }
            Node::Call {
                callee: Callee::Lib(l),
                first,
                n,
            } => {
                let arity_ok = match l {
                    Lib::If => n == 3,
                    Lib::Select => n >= 2,
                    Lib::Min | Lib::Max => n >= 1,
                    Lib::Atan2 => n == 2,
                    // The primitive's real arguments, whatever the frame.
                    Lib::Arg => n == 1,
                    _ => l.unary().is_some() && n == 1,
                };
                arity_ok
                    && self
                        .code
                        .args(first, n)
                        .iter()
                        .all(|&a| self.inline_body(a, k, depth, nodes))
            }
            Node::Call {
                callee: Callee::Slot(s),
                first,
                n,
            } => {
                let slot = &self.code.slots[s as usize];
                matches!(slot.def, Def::Func { .. })
                    && self.can_inline(s, first, n, depth + 1, nodes)
            }
            Node::Call { .. } => false,
        }
    }

    /// The arguments of a call get blocks of their own (run lazily in this frame).
    fn args_later(&mut self, first: u32, k: u16) {
        let list = self.code.args(first, k);
        self.pending.extend_from_slice(list);
    }

    /// Argument `i` of a library call inline, or the fatal error of a missing one
    /// (false).
    fn lib_arg(&mut self, l: Lib, list: &[NodeId], i: usize, site: NodeId) -> bool {
        match list.get(i) {
            Some(&a) => {
                self.node(a);
                true
            }
            None => {
                self.fail(Fail::FewLibArgs(l, site), site);
                false
            }
        }
    }

    /// Arguments `0..k` of a library call, each but the last pushed; false when one is
    /// missing (its fatal error is then emitted).
    fn lib_args(&mut self, l: Lib, list: &[NodeId], k: usize, site: NodeId) -> bool {
        for i in 0..k {
            if !self.lib_arg(l, list, i, site) {
                return false;
            }
            if i + 1 < k {
                self.emit(Ins::Push, site);
            }
        }
        true
    }

    fn lib(&mut self, l: Lib, first: u32, k: u16, site: NodeId) {
        let list = self.code.args(first, k);
        if let Some(f) = l.unary() {
            if self.lib_arg(l, list, 0, site) {
                self.emit(Ins::Unary(f), site);
            }
            return;
        }
        match l {
            Lib::If => {
                if !self.lib_arg(l, list, 0, site) {
                    return;
                }
                let jf = self.emit(Ins::JumpUnlessPos(NONE), site);
                self.lib_arg(l, list, 1, site);
                let je = self.emit(Ins::Jump(NONE), site);
                let else_at = self.here();
                self.lib_arg(l, list, 2, site);
                let end = self.here();
                self.out.ins[jf] = Ins::JumpUnlessPos(else_at);
                self.out.ins[je] = Ins::Jump(end);
            }
            Lib::Select => {
                if !self.lib_arg(l, list, 0, site) {
                    return;
                }
                let count = list.len() - 1;
                let at = self.out.table.len();
                self.out.table.resize(at + count + 1, NONE);
                self.emit(
                    Ins::Select {
                        count: count as u16,
                        at: at as u32,
                    },
                    site,
                );
                let mut ends = Vec::with_capacity(count);
                for (kk, &a) in list.iter().enumerate().skip(1) {
                    self.out.table[at + kk] = self.here();
                    self.node(a);
                    ends.push(self.emit(Ins::Jump(NONE), site));
                }
                let end = self.here();
                self.out.table[at] = end;
                for pc in ends {
                    self.out.ins[pc] = Ins::Jump(end);
                }
            }
            Lib::Min | Lib::Max => {
                // From the last argument backwards, as the tree walker (and Radiance).
                if list.is_empty() {
                    self.fail(Fail::FewLibArgs(l, site), site);
                    return;
                }
                for (i, &a) in list.iter().enumerate().rev() {
                    self.node(a);
                    if i > 0 {
                        self.emit(Ins::Push, site);
                    }
                }
                self.emit(
                    Ins::MinMax {
                        max: l == Lib::Max,
                        n: list.len() as u16,
                    },
                    site,
                );
            }
            Lib::Atan2 => {
                if self.lib_args(l, list, 2, site) {
                    self.emit(Ins::Atan2, site);
                }
            }
            Lib::Arg => {
                if self.lib_arg(l, list, 0, site) {
                    self.emit(Ins::ArgFn(site), site);
                }
            }
            _ => {
                if self.lib_args(l, list, 3, site) {
                    self.emit(Ins::Noise(l), site);
                }
            }
        }
    }
}
