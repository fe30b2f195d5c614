//! The parser: Radiance's grammar (§1.3 of the format reference) straight into the node
//! arena, with names bound at parse time and constants folded as they are built
//! ([`super::fold`]).

use super::builder::CalBuilder;
use super::code::{Callee, Loc, Node, NodeId};
use super::lexer::{Lexer, Tok};
use super::{CalError, Ctx, Dialect, ExprId};

/// How deeply `(`, calls and `^` may nest in one expression (the parser's own recursion).
const MAX_NEST: u32 = 200;

/// A parse error: where and what.
#[derive(Debug, Clone)]
pub(crate) struct PErr {
    pub line: u32,
    pub col: u32,
    pub message: String,
}

pub(crate) struct Parser<'a, 'b> {
    pub b: &'b mut CalBuilder,
    lx: Lexer<'a>,
    pub tok: Tok,
    pub line: u32,
    pub col: u32,
    /// The context names are qualified with ("" = global).
    pub ctx: String,
    /// Parameters of the function being defined.
    pub params: Vec<String>,
    /// File index for node locations.
    pub file: u32,
    /// Whether node locations carry lines (false for a primitive's expression, whose
    /// origin already names its line).
    pub lines: bool,
    nest: u32,
}

impl<'a, 'b> Parser<'a, 'b> {
    pub fn new(
        b: &'b mut CalBuilder,
        text: &'a [u8],
        ctx: String,
        file: u32,
        lines: bool,
    ) -> Result<Parser<'a, 'b>, PErr> {
        let mut p = Parser {
            b,
            lx: Lexer::new(text),
            tok: Tok::Eof,
            line: 1,
            col: 1,
            ctx,
            params: Vec::new(),
            file,
            lines,
            nest: 0,
        };
        p.advance()?;
        Ok(p)
    }

    pub fn err(&self, message: impl Into<String>) -> PErr {
        PErr {
            line: self.line,
            col: self.col,
            message: message.into(),
        }
    }

    pub fn advance(&mut self) -> Result<(), PErr> {
        match self.lx.next() {
            Ok((t, line, col)) => {
                self.tok = t;
                self.line = line;
                self.col = col;
                Ok(())
            }
            Err(e) => Err(PErr {
                line: e.line,
                col: e.col,
                message: e.message.to_string(),
            }),
        }
    }

    fn is(&self, c: u8) -> bool {
        self.tok == Tok::Char(c)
    }

    fn expect(&mut self, c: u8, message: &str) -> Result<(), PErr> {
        if !self.is(c) {
            return Err(self.err(message));
        }
        self.advance()
    }

    /// The location of the current token, for nodes.
    pub fn loc(&self) -> Loc {
        Loc {
            file: self.file,
            line: if self.lines { self.line } else { 0 },
        }
    }

    /// A whole file: statements separated by `;`.
    pub fn statements(&mut self) -> Result<(), PErr> {
        loop {
            match self.tok {
                Tok::Eof => return Ok(()),
                Tok::Char(b';') => {
                    self.advance()?;
                    continue;
                }
                _ => {}
            }
            self.statement()?;
            match self.tok {
                Tok::Char(b';') => self.advance()?,
                Tok::Eof => return Ok(()),
                _ => return Err(self.err("';' expected")),
            }
        }
    }

    fn statement(&mut self) -> Result<(), PErr> {
        let line = self.line;
        let name = match self.tok.clone() {
            Tok::Chan(n) if self.b.opts.dialect == Dialect::Rcalc => {
                self.advance()?;
                self.expect(b'=', "'=' expected")?;
                let e = self.expression()?;
                self.b.add_output(n, e);
                return Ok(());
            }
            Tok::Name(n) if !n.trim_matches('`').is_empty() => n,
            _ => return Err(self.err("illegal variable name")),
        };
        self.advance()?;
        let mut params = Vec::new();
        if self.is(b'(') {
            loop {
                self.advance()?;
                match &self.tok {
                    Tok::Name(p) if !p.contains('`') => params.push(p.clone()),
                    _ => return Err(self.err("illegal variable name")),
                }
                self.advance()?;
                if !self.is(b',') {
                    break;
                }
            }
            self.expect(b')', "')' expected")?;
        }
        let konst = match self.tok {
            Tok::Char(b'=') => false,
            Tok::Char(b':') => true,
            _ => return Err(self.err("'=' or ':' expected")),
        };
        self.advance()?;
        self.params = params;
        let body = self.expression();
        let nparams = self.params.len();
        self.params.clear();
        let body = body?;
        let loc = Loc {
            file: self.file,
            line,
        };
        self.b.define(&name, &self.ctx, nparams, konst, body, loc);
        Ok(())
    }

    /// One expression (E1).
    pub fn expression(&mut self) -> Result<NodeId, PErr> {
        let mut left = self.term()?;
        while let Tok::Char(c @ (b'+' | b'-')) = self.tok {
            self.advance()?;
            let right = self.term()?;
            left = self.binary(c, left, right)?;
        }
        Ok(left)
    }

    /// E2: products and quotients.
    fn term(&mut self) -> Result<NodeId, PErr> {
        let mut left = self.power()?;
        while let Tok::Char(c @ (b'*' | b'/')) = self.tok {
            self.advance()?;
            let right = self.power()?;
            left = self.binary(c, left, right)?;
        }
        Ok(left)
    }

    /// E3: `^`, right-associative. Every recursion of the grammar passes here.
    fn power(&mut self) -> Result<NodeId, PErr> {
        self.nest += 1;
        if self.nest > MAX_NEST {
            return Err(self.err(format!(
                "expression nested too deeply (more than {MAX_NEST} levels)"
            )));
        }
        let base = self.signed()?;
        let r = if self.is(b'^') {
            self.advance()?;
            let exp = self.power()?;
            self.binary(b'^', base, exp)
        } else {
            Ok(base)
        };
        self.nest -= 1;
        r
    }

    /// E4: a unary sign binds tighter than `^`.
    fn signed(&mut self) -> Result<NodeId, PErr> {
        if self.is(b'-') {
            self.advance()?;
            let e = self.primary()?;
            self.negate(e)
        } else if self.is(b'+') {
            self.advance()?;
            self.primary()
        } else {
            self.primary()
        }
    }

    /// E5: parentheses, numbers, channels, names and calls.
    fn primary(&mut self) -> Result<NodeId, PErr> {
        let loc = self.loc();
        match self.tok.clone() {
            Tok::Char(b'(') => {
                self.advance()?;
                let e = self.expression()?;
                self.expect(b')', "')' expected")?;
                Ok(e)
            }
            Tok::Num(v) => {
                self.advance()?;
                self.node(Node::Num(v), loc, &[])
            }
            Tok::Chan(n) if self.b.opts.dialect != Dialect::Plain => {
                self.advance()?;
                self.node(Node::Chan(n), loc, &[])
            }
            Tok::Name(name) => {
                self.advance()?;
                if !self.is(b'(') {
                    return self.reference(&name, loc);
                }
                let mut args = Vec::new();
                loop {
                    self.advance()?;
                    args.push(self.expression()?);
                    if !self.is(b',') {
                        break;
                    }
                }
                self.expect(b')', "')' expected")?;
                if args.len() > u16::MAX as usize {
                    return Err(self.err("too many arguments"));
                }
                let callee = match self.param_index(&name) {
                    Some(i) => Callee::Param(i),
                    None => Callee::Slot(self.b.lookup_ref(&name, &self.ctx)),
                };
                self.call(callee, args, loc)
            }
            _ => Err(self.err("unexpected character")),
        }
    }

    /// The index of `name` among the parameters of the function being defined.
    pub fn param_index(&self, name: &str) -> Option<u16> {
        self.params
            .iter()
            .position(|p| p == name)
            .map(|i| i.min(u16::MAX as usize) as u16)
    }
}

/// The builder's entry points into the parser (here, so that the builder does not depend on
/// the parser that drives it).
impl CalBuilder {
    /// Compile the statements of `text` (named `file` in messages) in context `ctx`.
    pub fn load_text(&mut self, text: &[u8], file: &str, ctx: Ctx) -> Result<(), CalError> {
        let id = self.file_id(file);
        let cstr = self.ctxs[ctx.0 as usize].clone();
        let r = Parser::new(self, text, cstr, id, true).and_then(|mut p| p.statements());
        r.map_err(|e| CalError {
            file: file.to_string(),
            line: e.line,
            col: e.col,
            message: e.message,
        })
    }

    /// Compile a primitive's expression argument in context `ctx`; `origin` is the
    /// primitive's `file:line`, used in messages.
    pub fn expr(&mut self, text: &str, ctx: Ctx, origin: &str) -> Result<ExprId, CalError> {
        let id = self.file_id(origin);
        let cstr = self.ctxs[ctx.0 as usize].clone();
        let r = Parser::new(self, text.as_bytes(), cstr, id, false).and_then(|mut p| {
            let e = p.expression()?;
            match p.tok {
                Tok::Eof => Ok(e),
                _ => Err(p.err("unexpected character")),
            }
        });
        match r {
            Ok(e) => {
                self.exprs.push(e);
                Ok(ExprId(self.exprs.len() as u32 - 1))
            }
            Err(e) => Err(expr_error(origin, text, e)),
        }
    }
}

/// A parse error in a primitive's expression: the origin's file and line, the column in
/// the expression.
fn expr_error(origin: &str, text: &str, e: PErr) -> CalError {
    let (file, line) = match origin.rsplit_once(':') {
        Some((f, l)) if l.parse::<u32>().is_ok() => (f.to_string(), l.parse().unwrap_or(0)),
        _ => (origin.to_string(), 0),
    };
    CalError {
        file,
        line: line.max(1),
        col: e.col,
        message: format!("{} in expression \"{text}\"", e.message),
    }
}
