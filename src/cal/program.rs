//! [`Program`] (immutable, shared by threads) and [`Evaluation`] (one tick of Radiance's
//! evaluation clock, with this thread's variable cache).

use super::code::{Code, NodeId};
use super::compile::Compiled;
use super::eval::{call_slot, ArgSrc, Entry, Frame, Trap};
use super::pure::Pure;
use super::vm::Vm;
use super::{Env, EvalError, ExprId, FuncRef};
use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicU64, Ordering};

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// Caches kept per thread, for the programs it used last.
const POOL_SIZE: usize = 16;

thread_local! {
    /// Variable caches and value stacks not in use, by program id.
    static POOL: RefCell<Vec<(u64, Box<Scratch>)>> = const { RefCell::new(Vec::new()) };
    /// This thread's evaluation clock.
    static TICK: Cell<u64> = const { Cell::new(0) };
}

/// What one evaluation writes: the variable cache and the value stack.
struct Scratch {
    cache: Vec<Entry>,
    stack: Vec<f64>,
}

impl Scratch {
    /// A fresh one for a program of `n` slots (boxed: an evaluation moves a pointer in
    /// and out of the pool, not the two vectors).
    fn boxed(n: usize) -> Box<Scratch> {
        Box::new(Scratch {
            cache: vec![Entry::default(); n],
            stack: Vec::with_capacity(64),
        })
    }
}

/// Compiled definitions and expressions. Immutable; evaluate it from any number of threads
/// with [`Program::begin`].
#[derive(Debug)]
pub struct Program {
    code: Code,
    /// The run-time form of `code`.
    vm: Compiled,
    /// The block of each expression.
    exprs: Vec<u32>,
    /// The node of each expression (its pure form; the tree walker's cross-check in tests).
    roots: Vec<NodeId>,
    outputs: Vec<(u32, ExprId)>,
    id: u64,
}

impl Program {
    pub(crate) fn new(code: Code, exprs: Vec<NodeId>, outputs: Vec<(u32, ExprId)>) -> Program {
        let (vm, blocks) = Compiled::new(&code, &exprs);
        Program {
            code,
            vm,
            exprs: blocks,
            roots: exprs,
            outputs,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// Start one evaluation (Radiance's clock tick for one (modifier, ray) pair): every
    /// [`Evaluation::eval`] and [`Evaluation::call`] made through it shares variable values.
    /// Evaluations may nest on one thread; each has its own cache.
    pub fn begin<'a>(&'a self, env: &'a Env<'a>) -> Evaluation<'a> {
        let tick = TICK.with(|t| {
            t.set(t.get() + 1);
            t.get()
        });
        let n = self.code.slots.len();
        let scratch = POOL
            .try_with(|p| {
                let mut p = p.borrow_mut();
                p.iter()
                    .rposition(|(id, _)| *id == self.id)
                    .map(|i| p.swap_remove(i).1)
            })
            .ok()
            .flatten()
            .unwrap_or_else(|| Scratch::boxed(n));
        Evaluation {
            prog: self,
            env,
            scratch: Some(scratch),
            tick,
        }
    }

    /// Function calls left in the code of expression `e` itself (those compiled inline
    /// are not calls).
    #[cfg(test)]
    pub(crate) fn calls_in(&self, e: ExprId) -> usize {
        self.vm.calls_in(self.exprs[e.0 as usize])
    }

    /// Expressions `es` (one to six) as one [`Pure`] expression with a root each, when
    /// they are pure (see [`Pure`]).
    pub fn pure_exprs(&self, es: &[ExprId]) -> Option<Pure> {
        self.pure_exprs_with(es, None)
    }

    /// [`Program::pure_exprs`] for evaluations that will always pass the real arguments
    /// `args` (a primitive's own): `arg(n)` and what follows from it alone are computed once
    /// (the same values; an evaluation must then pass these `args`).
    pub fn pure_exprs_with(&self, es: &[ExprId], args: Option<&[f64]>) -> Option<Pure> {
        let roots = es
            .iter()
            .map(|e| self.roots.get(e.0 as usize).copied())
            .collect::<Option<Vec<_>>>()?;
        super::pure::expand(&self.code, &roots, false, args)
    }

    /// Expression `e` as a [`Pure`] expression, when it is one.
    pub fn pure_expr(&self, e: ExprId) -> Option<Pure> {
        self.pure_exprs(&[e])
    }

    /// Function `f`'s body as a [`Pure`] expression of the call's values, when it is one.
    pub fn pure_func(&self, f: FuncRef) -> Option<Pure> {
        self.pure_func_with(f, None)
    }

    /// [`Program::pure_func`] with the real arguments known ([`Program::pure_exprs_with`]).
    pub fn pure_func_with(&self, f: FuncRef, args: Option<&[f64]>) -> Option<Pure> {
        use super::code::Def;
        match self.code.slots.get(f.0 as usize)?.def {
            Def::Func { body, .. } => super::pure::expand(&self.code, &[body], true, args),
            _ => None,
        }
    }

    /// The rcalc-style outputs (`$N = expr`) in definition order.
    pub fn outputs(&self) -> &[(u32, ExprId)] {
        &self.outputs
    }

    /// Number of compiled nodes (a size figure for tests and statistics).
    pub fn node_count(&self) -> usize {
        self.code.nodes.len()
    }
}

/// One evaluation of a [`Program`] for one environment.
pub struct Evaluation<'a> {
    prog: &'a Program,
    env: &'a Env<'a>,
    /// Always Some until dropped (then back in the pool).
    scratch: Option<Box<Scratch>>,
    tick: u64,
}

impl Evaluation<'_> {
    fn run(&mut self, f: impl FnOnce(&mut Vm) -> Result<f64, Trap>) -> Result<f64, EvalError> {
        let top = Frame::top();
        let n = self.prog.code.slots.len();
        let scratch = self.scratch.get_or_insert_with(|| Scratch::boxed(n));
        let mut m = Vm {
            top: &top,
            prog: &self.prog.vm,
            code: &self.prog.code,
            env: self.env,
            cache: &mut scratch.cache,
            stack: &mut scratch.stack,
            tick: self.tick,
            depth: 0,
            origin: super::eval::stack_here(),
            fatal: None,
        };
        let r = f(&mut m);
        r.map_err(|t| match t {
            Trap::Domain => EvalError::Domain,
            Trap::Range => EvalError::Range,
            Trap::Fatal => EvalError::Fatal(m.fatal.take().unwrap_or_default()),
        })
    }

    /// The value of a compiled expression.
    pub fn eval(&mut self, e: ExprId) -> Result<f64, EvalError> {
        let block = self.prog.exprs[e.0 as usize];
        self.run(|m| m.run(block, &Frame::top()))
    }

    /// [`Evaluation::eval`] by the tree walker (the reference the run-time machine is
    /// checked against).
    #[cfg(test)]
    pub(crate) fn eval_tree(&mut self, e: ExprId) -> Result<f64, EvalError> {
        let node = self.prog.roots[e.0 as usize];
        let n = self.prog.code.slots.len();
        let scratch = self.scratch.get_or_insert_with(|| Scratch::boxed(n));
        let mut m = super::eval::Machine {
            code: &self.prog.code,
            env: Some(self.env),
            cache: &mut scratch.cache,
            tick: self.tick,
            depth: 0,
            stack: super::eval::stack_here(),
            fatal: None,
        };
        let r = m.eval(node, &Frame::top());
        r.map_err(|t| match t {
            Trap::Domain => EvalError::Domain,
            Trap::Range => EvalError::Range,
            Trap::Fatal => EvalError::Fatal(m.fatal.take().unwrap_or_default()),
        })
    }

    /// Call a function with values.
    pub fn call(&mut self, f: FuncRef, args: &[f64]) -> Result<f64, EvalError> {
        self.run(|m| call_slot(m, f.0, ArgSrc::Values(args), u32::MAX))
    }
}

impl Drop for Evaluation<'_> {
    fn drop(&mut self) {
        let Some(scratch) = self.scratch.take() else {
            return;
        };
        let id = self.prog.id;
        let _ = POOL.try_with(|p| {
            if let Ok(mut p) = p.try_borrow_mut() {
                if p.len() >= POOL_SIZE {
                    p.remove(0);
                }
                p.push((id, scratch));
            }
        });
    }
}

impl Program {
    /// The number of parameters of `f`'s definition: Some(n) for a defined function,
    /// Some(0) for a variable or constant, None for a library function or an undefined
    /// name.
    pub fn params(&self, f: FuncRef) -> Option<usize> {
        use super::code::Def;
        match self.code.slots.get(f.0 as usize)?.def {
            Def::Func { nparams, .. } => Some(nparams as usize),
            Def::Var { .. } | Def::Num(_) | Def::Brdf(_) => Some(0),
            Def::None => None,
        }
    }
}

impl Evaluation<'_> {
    /// The program being evaluated.
    pub fn program(&self) -> &Program {
        self.prog
    }
}
