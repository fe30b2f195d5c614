//! The compiled form: a node arena with resolved name slots, shared by the builder (which
//! evaluates constant expressions while compiling) and the finished [`super::Program`].

use super::library::Lib;

/// Index of a node in [`Code::nodes`].
pub(crate) type NodeId = u32;
/// Index of a name slot in [`Code::slots`].
pub(crate) type SlotId = u32;

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

/// What a call calls.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Callee {
    /// The definition of a name slot (a function, or its library fallback).
    Slot(SlotId),
    /// A library function (a slot without definition, resolved when the program is
    /// finished).
    Lib(Lib),
    /// The function whose name the caller passed as this parameter.
    Param(u16),
}

/// One node of an expression tree. Children are node ids; call arguments are a range of
/// [`Code::arglist`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Node {
    Num(f64),
    /// Ray channel `$N` (1-based, as written).
    Chan(u32),
    Var(SlotId),
    /// A parameter of the function being evaluated.
    Param(u16),
    Neg(NodeId),
    Bin(Op, NodeId, NodeId),
    Call {
        callee: Callee,
        first: u32,
        n: u16,
    },
}

/// Where something is: a file (index into [`Code::files`]) and a 1-based line (0 when the
/// "file" is an expression's origin that already holds its line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Loc {
    pub file: u32,
    pub line: u32,
}

/// The definition a name slot holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Def {
    /// Referenced but not (yet) defined.
    None,
    /// A constant whose value is known.
    Num(f64),
    /// `v = e` (konst false) or `v : e` whose expression did not fold (konst true).
    Var { expr: NodeId, konst: bool },
    /// `f(a, …) = e` or `f(a, …) : e` (konst).
    Func {
        nparams: u16,
        body: NodeId,
        konst: bool,
    },
    /// One of the BRDF variables `NxP NyP NzP RdotP CrP CgP CbP` (index into
    /// [`super::Env::brdf`]).
    Brdf(u8),
}

/// A name slot: a fully qualified name and its current definition.
#[derive(Debug, Clone)]
pub(crate) struct Slot {
    pub name: String,
    pub def: Def,
    /// Where the current definition was made.
    pub def_loc: Loc,
    /// The library function this name falls back to when it has no definition.
    pub lib: Option<Lib>,
}

/// Nodes, argument lists, name slots and locations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Code {
    pub nodes: Vec<Node>,
    /// Where each node was written (parallel to `nodes`).
    pub locs: Vec<Loc>,
    pub arglist: Vec<NodeId>,
    pub slots: Vec<Slot>,
    pub files: Vec<String>,
}

impl Code {
    /// `file:line` of a location.
    pub fn place(&self, loc: Loc) -> String {
        let f = self
            .files
            .get(loc.file as usize)
            .map_or("?", |s| s.as_str());
        if loc.line == 0 {
            f.to_string()
        } else {
            format!("{f}:{}", loc.line)
        }
    }

    /// The argument node ids of a call.
    pub fn args(&self, first: u32, n: u16) -> &[NodeId] {
        &self.arglist[first as usize..first as usize + n as usize]
    }

    /// A slot's name as Radiance prints it (without the context of a global name).
    pub fn name(&self, s: SlotId) -> &str {
        &self.slots[s as usize].name
    }

    /// Resolve what can be resolved once every definition is final: calls to undefined
    /// names with a library fallback call the library directly, references to numbers and
    /// to plain channel variables become the number or the channel.
    pub fn link(&mut self) {
        for i in 0..self.nodes.len() {
            match self.nodes[i] {
                Node::Call {
                    callee: Callee::Slot(s),
                    first,
                    n,
                } => {
                    let slot = &self.slots[s as usize];
                    if let (Def::None, Some(l)) = (slot.def, slot.lib) {
                        self.nodes[i] = Node::Call {
                            callee: Callee::Lib(l),
                            first,
                            n,
                        };
                    }
                }
                // A name whose value is a number or a ray channel is read directly
                // (channel names such as Px are `Px = $7`): no cache needed.
                Node::Var(s) => match self.slots[s as usize].def {
                    Def::Num(v) => self.nodes[i] = Node::Num(v),
                    Def::Var { expr, .. } => {
                        if let n @ (Node::Num(_) | Node::Chan(_)) = self.nodes[expr as usize] {
                            self.nodes[i] = n;
                        }
                    }
                    _ => {}
                },
                _ => {}
            }
        }
    }
}
