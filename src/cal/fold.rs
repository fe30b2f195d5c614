//! Building nodes with Radiance's constant folding (§1.4 of the format reference):
//! operators over numbers are computed, `x*0 0*x 0/x 0^x` become 0, `x^0 1^x` become 1,
//! `x/c` becomes `x*(1/c)`; references to constants and calls of constant functions with
//! constant arguments are evaluated at parse time. Any error while folding is fatal.

use super::code::{Callee, Def, Loc, Node, NodeId, Op, SlotId};
use super::eval::{binop, Frame, Trap};
use super::parser::{PErr, Parser};

/// The deepest expression tree accepted (deeper ones could not be evaluated within
/// [`super::eval::MAX_DEPTH`]).
pub(crate) const MAX_NODE_DEPTH: u32 = 2000;

impl Parser<'_, '_> {
    /// Add a node whose children are `kids`.
    pub fn node(&mut self, n: Node, loc: Loc, kids: &[NodeId]) -> Result<NodeId, PErr> {
        let depth = 1 + kids
            .iter()
            .map(|&k| self.b.depth[k as usize])
            .max()
            .unwrap_or(0);
        if depth > MAX_NODE_DEPTH {
            return Err(self.err(format!(
                "expression too deep (more than {MAX_NODE_DEPTH} levels of operators)"
            )));
        }
        Ok(self.b.push_node(n, loc, depth))
    }

    fn num(&self, n: NodeId) -> Option<f64> {
        match self.b.code.nodes[n as usize] {
            Node::Num(v) => Some(v),
            _ => None,
        }
    }

    fn fold_error(&self, t: Trap, msg: Option<String>) -> PErr {
        match t {
            Trap::Fatal => self.err(msg.unwrap_or_else(|| "bad constant expression".into())),
            _ => self.err("bad constant expression"),
        }
    }

    /// `left op right` for an operator character.
    #[allow(clippy::redundant_guards)] // guards compare -0.0 and 0.0 alike, as Radiance
    pub fn binary(&mut self, c: u8, a: NodeId, b: NodeId) -> Result<NodeId, PErr> {
        let op = match c {
            b'+' => Op::Add,
            b'-' => Op::Sub,
            b'*' => Op::Mul,
            b'/' => Op::Div,
            _ => Op::Pow,
        };
        let loc = self.loc();
        if !self.b.opts.fold {
            return self.node(Node::Bin(op, a, b), loc, &[a, b]);
        }
        let (x, y) = (self.num(a), self.num(b));
        if let (Some(x), Some(y)) = (x, y) {
            return match binop(op, x, y) {
                Ok(v) => self.node(Node::Num(v), loc, &[]),
                Err(t) => Err(self.fold_error(t, None)),
            };
        }
        let to = match (op, x, y) {
            (Op::Mul, Some(z), _) | (Op::Mul, _, Some(z)) if z == 0.0 => Some(0.0),
            (Op::Div, _, Some(z)) if z == 0.0 => return Err(self.err("divide by zero constant")),
            (Op::Div, Some(z), _) if z == 0.0 => Some(0.0),
            (Op::Pow, Some(z), _) if z == 0.0 => Some(0.0),
            (Op::Pow, _, Some(z)) if z == 0.0 => Some(1.0),
            (Op::Pow, Some(z), _) if z == 1.0 => Some(1.0),
            _ => None,
        };
        if let Some(v) = to {
            return self.node(Node::Num(v), loc, &[]);
        }
        if let (Op::Div, Some(c)) = (op, y) {
            let inv = self.node(Node::Num(1.0 / c), loc, &[])?;
            return self.node(Node::Bin(Op::Mul, a, inv), loc, &[a, inv]);
        }
        self.node(Node::Bin(op, a, b), loc, &[a, b])
    }

    /// `-e`.
    pub fn negate(&mut self, e: NodeId) -> Result<NodeId, PErr> {
        let loc = self.loc();
        match self.num(e) {
            Some(v) if self.b.opts.fold => self.node(Node::Num(-v), loc, &[]),
            _ => self.node(Node::Neg(e), loc, &[e]),
        }
    }

    /// A reference to a name: a parameter, or a slot (folded when it holds a constant).
    pub fn reference(&mut self, name: &str, loc: Loc) -> Result<NodeId, PErr> {
        if let Some(i) = self.param_index(name) {
            return self.node(Node::Param(i), loc, &[]);
        }
        let s = self.b.lookup_ref(name, &self.ctx);
        if self.b.opts.fold {
            match self.b.code.slots[s as usize].def {
                Def::Num(v) => return self.node(Node::Num(v), loc, &[]),
                Def::Var { konst: true, .. } => {
                    let site = self.node(Node::Var(s), loc, &[])?;
                    let v = self.const_eval(|m| m.var(s, site))?;
                    // Evaluated once: the constant keeps this value from now on.
                    self.b.code.slots[s as usize].def = Def::Num(v);
                    return self.node(Node::Num(v), loc, &[]);
                }
                _ => {}
            }
        }
        self.node(Node::Var(s), loc, &[])
    }

    /// Whether slot `s` names a constant function (user `:` or constant library).
    fn const_func(&self, s: SlotId) -> bool {
        let slot = &self.b.code.slots[s as usize];
        match slot.def {
            Def::Func { konst, .. } => konst,
            Def::None => slot.lib.is_some_and(|l| l.is_const()),
            _ => false,
        }
    }

    /// A call, folded when the function and all its arguments are constant.
    pub fn call(&mut self, callee: Callee, args: Vec<NodeId>, loc: Loc) -> Result<NodeId, PErr> {
        let first = self.b.code.arglist.len() as u32;
        let n = args.len() as u16;
        self.b.code.arglist.extend_from_slice(&args);
        let site = self.node(Node::Call { callee, first, n }, loc, &args)?;
        let Callee::Slot(s) = callee else {
            return Ok(site);
        };
        if !self.b.opts.fold || !self.const_func(s) {
            return Ok(site);
        }
        let all_const = args.iter().all(|&a| match self.b.code.nodes[a as usize] {
            Node::Num(_) => true,
            Node::Var(v) => self.const_func(v),
            _ => false,
        });
        if !all_const {
            return Ok(site);
        }
        let v = self.const_eval(|m| m.eval(site, &Frame::top()))?;
        self.node(Node::Num(v), loc, &[])
    }

    /// Evaluate something in constant mode (no ray, no primitive).
    fn const_eval(
        &mut self,
        f: impl FnOnce(&mut super::eval::Machine) -> Result<f64, Trap>,
    ) -> Result<f64, PErr> {
        let mut m = super::eval::Machine {
            code: &self.b.code,
            env: None,
            cache: &mut [],
            tick: 0,
            depth: 0,
            stack: super::eval::stack_here(),
            fatal: None,
        };
        let r = f(&mut m);
        let msg = m.fatal.take();
        r.map_err(|t| self.fold_error(t, msg))
    }
}
