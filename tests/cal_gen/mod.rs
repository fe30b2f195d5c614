//! Random expressions for the function-language tests: a seeded grammar, a printer that
//! uses the fewest parentheses the precedence rules allow (plus some redundant ones), and a
//! direct reference evaluator with Radiance master's error rules.
#![allow(dead_code)]

/// xorshift64*.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}

/// An expression.
#[derive(Clone, Debug)]
pub enum E {
    /// A non-negative number and how to print it (0 plain, 1 `{:e}`, 2 leading dot).
    Num(f64, u8),
    Var(&'static str),
    Neg(Box<E>),
    Pos(Box<E>),
    Paren(Box<E>),
    Bin(u8, Box<E>, Box<E>),
    Call(&'static str, Vec<E>),
    /// `h(F, x)`: a function name passed as an argument.
    Pass(&'static str, Box<E>),
}

/// Whether `e` has a literal 0 (folding turns `0*x` into +0 whatever the sign of x, as
/// Radiance does, so `atan2` and divisions may then differ from the unfolded value).
pub fn has_zero(e: &E) -> bool {
    match e {
        E::Num(v, _) => *v == 0.0,
        E::Var(_) => false,
        E::Neg(a) | E::Pos(a) | E::Paren(a) | E::Pass(_, a) => has_zero(a),
        E::Bin(_, a, b) => has_zero(a) || has_zero(b),
        E::Call(_, args) => args.iter().any(has_zero),
    }
}

/// Whether `e` calls a noise function: their high octaves make a value depend on the last
/// bits of its arguments, which folding may round differently (`x / c` is `x * (1/c)`).
pub fn has_noise(e: &E) -> bool {
    match e {
        E::Num(..) | E::Var(_) => false,
        E::Neg(a) | E::Pos(a) | E::Paren(a) | E::Pass(_, a) => has_noise(a),
        E::Bin(_, a, b) => has_noise(a) || has_noise(b),
        E::Call(f, args) => NOISE.contains(f) || args.iter().any(has_noise),
    }
}

/// Whether `e` calls sin, cos, tan or rand: far from the origin (`sin(2.3e63)`), and for
/// rand everywhere, a last-bit difference of the argument changes their value entirely, so
/// a folded expression (whose divisions by constants are multiplications by reciprocals)
/// may differ from the reference (`rand(h(f, (2e4 - (c - 5) * b) / 1.5e0))`: 0.8523
/// folded against 0.8433).
pub fn has_periodic(e: &E) -> bool {
    const PERIODIC: [&str; 4] = ["sin", "cos", "tan", "rand"];
    match e {
        E::Num(..) | E::Var(_) => false,
        E::Neg(a) | E::Pos(a) | E::Paren(a) => has_periodic(a),
        E::Pass(f, a) => PERIODIC.contains(f) || has_periodic(a),
        E::Bin(_, a, b) => has_periodic(a) || has_periodic(b),
        E::Call(f, args) => PERIODIC.contains(f) || args.iter().any(has_periodic),
    }
}

/// The definitions every generated expression may use.
pub const DEFS: &str = "a = 0.7; b = -2.3; c = a*b + 1;
f(x) = x*x - 1; g(x,y) = if(x, y, -y); l(x,y,z) = if(x, y, z);
h(p,x) = p(x) + 1; sq2(x) = x*x;
";

pub fn var_value(v: &str) -> f64 {
    match v {
        "a" => 0.7,
        "b" => -2.3,
        _ => 0.7 * -2.3 + 1.0,
    }
}

const LIB1: [&str; 13] = [
    "rand", "floor", "ceil", "sqrt", "exp", "log", "log10", "sin", "cos", "tan", "asin", "acos",
    "atan",
];
const NOISE: [&str; 5] = ["noise3", "noise3x", "noise3y", "noise3z", "fnoise3"];
const PASSED: [&str; 4] = ["f", "sq2", "sin", "floor"];

/// Generator settings.
#[derive(Clone, Copy)]
pub struct Gen {
    pub noise: bool,
}

impl Gen {
    fn number(&self, r: &mut Rng) -> E {
        let v = match r.below(8) {
            0 => 0.0,
            1 | 2 => r.below(10) as f64,
            3 => r.below(64) as f64 / 8.0,
            4 => r.unit() * 10.0,
            5 => r.unit(),
            6 => 10f64.powi(r.below(13) as i32 - 6) * (1.0 + r.below(9) as f64),
            _ => (r.unit() * 1000.0).round() / 100.0,
        };
        E::Num(v, r.below(3) as u8)
    }

    pub fn expr(&self, r: &mut Rng, depth: u32) -> E {
        if depth == 0 || r.chance(0.25) {
            return if r.chance(0.65) {
                self.number(r)
            } else {
                E::Var(["a", "b", "c"][r.below(3)])
            };
        }
        let d = depth - 1;
        let sub = |r: &mut Rng| Box::new(self.expr(r, d));
        match r.below(100) {
            0..=39 => {
                let op = b"+-*/^"[r.below(5)];
                E::Bin(op, sub(r), sub(r))
            }
            40..=47 => E::Neg(sub(r)),
            48..=50 => E::Pos(sub(r)),
            51..=54 => E::Paren(sub(r)),
            55..=84 => self.lib_call(r, d),
            _ => match r.below(4) {
                0 => E::Call("f", vec![*sub(r)]),
                1 => E::Call("g", vec![*sub(r), *sub(r)]),
                2 => E::Call("l", vec![*sub(r), *sub(r), *sub(r)]),
                _ => E::Pass(PASSED[r.below(PASSED.len())], sub(r)),
            },
        }
    }

    fn lib_call(&self, r: &mut Rng, d: u32) -> E {
        let args = |r: &mut Rng, n: usize| (0..n).map(|_| self.expr(r, d)).collect::<Vec<_>>();
        if self.noise && r.chance(0.3) {
            return E::Call(NOISE[r.below(NOISE.len())], args(r, 3));
        }
        match r.below(8) {
            0 => E::Call("if", args(r, 3)),
            1 => {
                let n = 1 + r.below(4);
                let k = r.below(n + 2) as f64 + r.unit() - 0.5;
                let mut v = vec![if k < 0.0 {
                    E::Neg(Box::new(E::Num(-k, 0)))
                } else {
                    E::Num(k, 0)
                }];
                if r.chance(0.5) {
                    // Bounded: Radiance 6.0a crashes on indices beyond an int.
                    let m = E::Num(n as f64 + 1.5, 0);
                    v[0] = E::Bin(
                        b'*',
                        Box::new(E::Call("rand", vec![self.expr(r, d)])),
                        Box::new(m),
                    );
                }
                v.extend(args(r, n));
                E::Call("select", v)
            }
            2 => {
                let f = ["min", "max"][r.below(2)];
                let n = 1 + r.below(4);
                E::Call(f, args(r, n))
            }
            3 => E::Call("atan2", args(r, 2)),
            _ => E::Call(LIB1[r.below(LIB1.len())], args(r, 1)),
        }
    }
}

fn level(e: &E) -> u8 {
    match e {
        E::Bin(b'+' | b'-', ..) => 1,
        E::Bin(b'*' | b'/', ..) => 2,
        E::Bin(..) => 3,
        E::Neg(_) | E::Pos(_) => 4,
        _ => 5,
    }
}

fn num_text(v: f64, style: u8) -> String {
    if v == v.trunc() && v.abs() < 1e6 && style != 1 {
        return format!("{v}");
    }
    match style {
        1 => format!("{v:e}"),
        _ if (1e-4..1e6).contains(&v) => {
            let s = format!("{v}");
            match (style, s.strip_prefix('0')) {
                (2, Some(rest)) => rest.to_string(),
                _ => s,
            }
        }
        _ => format!("{v:e}"),
    }
}

/// The text of `e`, with numbers written as `(n+z0)` when `wrap` (z0 = 0 at run time, so
/// nothing folds).
pub fn print(e: &E, wrap: bool) -> String {
    let mut s = String::new();
    put(e, 1, wrap, &mut s);
    s
}

fn put(e: &E, need: u8, wrap: bool, s: &mut String) {
    if level(e) < need {
        s.push('(');
        put(e, 1, wrap, s);
        s.push(')');
        return;
    }
    match e {
        E::Num(v, st) if wrap => s.push_str(&format!("({}+z0)", num_text(*v, *st))),
        E::Num(v, st) => s.push_str(&num_text(*v, *st)),
        E::Var(n) => s.push_str(n),
        E::Neg(a) => {
            s.push('-');
            put(a, 5, wrap, s)
        }
        E::Pos(a) => {
            s.push('+');
            put(a, 5, wrap, s)
        }
        E::Paren(a) => {
            s.push('(');
            put(a, 1, wrap, s);
            s.push(')')
        }
        E::Bin(op, a, b) => {
            let (l, r) = match op {
                b'+' | b'-' => (1, 2),
                b'*' | b'/' => (2, 3),
                _ => (4, 3),
            };
            put(a, l, wrap, s);
            s.push(' ');
            s.push(*op as char);
            s.push(' ');
            put(b, r, wrap, s)
        }
        E::Call(f, args) => {
            s.push_str(f);
            s.push('(');
            for (i, a) in args.iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                put(a, 1, wrap, s);
            }
            s.push(')')
        }
        E::Pass(f, a) => {
            s.push_str("h(");
            s.push_str(f);
            s.push_str(", ");
            put(a, 1, wrap, s);
            s.push(')')
        }
    }
}

/// A reference evaluation's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Out {
    Val(f64),
    Domain,
    Range,
}

/// The reference evaluator (master's rules). `unsafe_6a` is set when Radiance 6.0a would
/// stop with a fatal error instead (a `select` index beyond an int).
pub struct Ref {
    pub unsafe_6a: bool,
    /// Relative perturbation of noise values (to find ill-conditioned expressions).
    pub perturb: f64,
}

impl Ref {
    pub fn new() -> Ref {
        Ref {
            unsafe_6a: false,
            perturb: 0.0,
        }
    }
}

fn check(v: f64) -> Result<f64, Out> {
    if v.is_nan() {
        Err(Out::Domain)
    } else if v.is_infinite() {
        Err(Out::Range)
    } else {
        Ok(v)
    }
}

#[allow(clippy::approx_constant)] // Radiance's constants
fn rand(x: f64) -> f64 {
    let mut x = x * (1.0 / (1.0 + x * x) + 2.71828182845904);
    x += 0.785398163397447 - x.floor();
    x = 1e5 / x;
    x - x.floor()
}

fn unary(f: &str, x: f64) -> f64 {
    match f {
        "rand" => rand(x),
        "floor" => x.floor(),
        "ceil" => x.ceil(),
        "sqrt" => x.sqrt(),
        "exp" => x.exp(),
        "log" => x.ln(),
        "log10" => x.log10(),
        "sin" => x.sin(),
        "cos" => x.cos(),
        "tan" => x.tan(),
        "asin" => x.asin(),
        "acos" => x.acos(),
        "atan" => x.atan(),
        _ => panic!("{f}"),
    }
}

fn noise(f: &str, x: f64, y: f64, z: f64, p: f64) -> f64 {
    use tessera::cal::{fnoise3, noise3};
    let eps = 0.0005;
    let d =
        |q: [f64; 3]| (noise3(x, y, z) * (1.0 + p) - noise3(q[0], q[1], q[2]) * (1.0 - p)) / eps;
    match f {
        "noise3" => noise3(x, y, z) * (1.0 + p),
        "noise3x" => d([x - eps, y, z]),
        "noise3y" => d([x, y - eps, z]),
        "noise3z" => d([x, y, z - eps]),
        _ => fnoise3(x, y, z) * (1.0 + p),
    }
}

impl Ref {
    pub fn eval(&mut self, e: &E) -> Result<f64, Out> {
        match e {
            E::Num(v, _) => Ok(*v),
            E::Var(n) => Ok(var_value(n)),
            E::Neg(a) => Ok(-self.eval(a)?),
            E::Pos(a) | E::Paren(a) => self.eval(a),
            E::Bin(op, a, b) => {
                let x = self.eval(a)?;
                let y = self.eval(b)?;
                match op {
                    b'+' => Ok(x + y),
                    b'-' => Ok(x - y),
                    b'*' => Ok(x * y),
                    b'/' if y == 0.0 => Err(Out::Range),
                    b'/' => Ok(x / y),
                    _ => check(x.powf(y)),
                }
            }
            E::Call(f, args) => self.call(f, args),
            E::Pass(f, a) => {
                let x = self.eval(a)?;
                let v = match *f {
                    "f" => x * x - 1.0,
                    "sq2" => x * x,
                    other => check(unary(other, x))?,
                };
                Ok(v + 1.0)
            }
        }
    }

    fn call(&mut self, f: &str, args: &[E]) -> Result<f64, Out> {
        match f {
            "if" | "l" => {
                let c = self.eval(&args[0])?;
                self.eval(&args[if c > 0.0 { 1 } else { 2 }])
            }
            "g" => {
                let x = self.eval(&args[0])?;
                let y = self.eval(&args[1])?;
                Ok(if x > 0.0 { y } else { -y })
            }
            "f" => {
                let x = self.eval(&args[0])?;
                Ok(x * x - 1.0)
            }
            "select" => {
                let d = self.eval(&args[0])? + 0.5;
                if d.is_nan() || d < 0.0 {
                    return Err(Out::Domain);
                }
                if d >= 2147483647.0 {
                    self.unsafe_6a = true;
                }
                let k = d.trunc();
                let count = (args.len() - 1) as f64;
                if k == 0.0 {
                    Ok(count)
                } else if k > count {
                    Err(Out::Domain)
                } else {
                    self.eval(&args[k as usize])
                }
            }
            "min" | "max" => {
                let n = args.len();
                let mut best = self.eval(&args[n - 1])?;
                for i in (0..n - 1).rev() {
                    let a = self.eval(&args[i])?;
                    if (f == "min" && a < best) || (f == "max" && a > best) {
                        best = a;
                    }
                }
                check(best)
            }
            "atan2" => {
                let y = self.eval(&args[0])?;
                let x = self.eval(&args[1])?;
                check(y.atan2(x))
            }
            n if NOISE.contains(&n) => {
                let x = self.eval(&args[0])?;
                let y = self.eval(&args[1])?;
                let z = self.eval(&args[2])?;
                check(noise(n, x, y, z, self.perturb))
            }
            n => {
                let x = self.eval(&args[0])?;
                check(unary(n, x))
            }
        }
    }
}

/// The outcome of Tessera's evaluation in the same terms.
pub fn out_of(r: Result<f64, tessera::cal::EvalError>) -> Result<f64, Out> {
    use tessera::cal::EvalError;
    match r {
        Ok(v) => Ok(v),
        Err(EvalError::Domain) => Err(Out::Domain),
        Err(EvalError::Range) => Err(Out::Range),
        Err(EvalError::Fatal(m)) => panic!("fatal: {m}"),
    }
}

/// Equal outcomes (NaN equals NaN).
pub fn same(a: Result<f64, Out>, b: Result<f64, Out>) -> bool {
    match (a, b) {
        (Ok(x), Ok(y)) => x == y || (x.is_nan() && y.is_nan()),
        (x, y) => x == y,
    }
}
