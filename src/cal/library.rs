//! The library functions (Radiance's calfunc.c set and the renderer's additions, §1.7 of
//! the format reference). The evaluator ([`super::eval`]) calls them with lazy
//! arguments; this file holds their names, their kinds and the plain math.

use super::Dialect;

/// A library function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Lib {
    If,
    Select,
    Min,
    Max,
    Rand,
    Floor,
    Ceil,
    Sqrt,
    Exp,
    Log,
    Log10,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    // The renderer's functions.
    Arg,
    Erf,
    Erfc,
    Noise3,
    Noise3x,
    Noise3y,
    Noise3z,
    Fnoise3,
}

const CALFUNC: [(&str, Lib); 18] = [
    ("if", Lib::If),
    ("select", Lib::Select),
    ("min", Lib::Min),
    ("max", Lib::Max),
    ("rand", Lib::Rand),
    ("floor", Lib::Floor),
    ("ceil", Lib::Ceil),
    ("sqrt", Lib::Sqrt),
    ("exp", Lib::Exp),
    ("log", Lib::Log),
    ("log10", Lib::Log10),
    ("sin", Lib::Sin),
    ("cos", Lib::Cos),
    ("tan", Lib::Tan),
    ("asin", Lib::Asin),
    ("acos", Lib::Acos),
    ("atan", Lib::Atan),
    ("atan2", Lib::Atan2),
];

const RENDERER: [(&str, Lib); 8] = [
    ("arg", Lib::Arg),
    ("erf", Lib::Erf),
    ("erfc", Lib::Erfc),
    ("noise3", Lib::Noise3),
    ("noise3x", Lib::Noise3x),
    ("noise3y", Lib::Noise3y),
    ("noise3z", Lib::Noise3z),
    ("fnoise3", Lib::Fnoise3),
];

impl Lib {
    /// The library function of this (unqualified) name in a dialect.
    pub fn lookup(name: &str, dialect: Dialect) -> Option<Lib> {
        let found = CALFUNC.iter().find(|(n, _)| *n == name);
        let found = match (found, dialect) {
            (None, Dialect::Renderer) => RENDERER.iter().find(|(n, _)| *n == name),
            (f, _) => f,
        };
        found.map(|(_, l)| *l)
    }

    /// The function's name.
    pub fn name(self) -> &'static str {
        CALFUNC
            .iter()
            .chain(RENDERER.iter())
            .find(|(_, l)| *l == self)
            .map_or("?", |(n, _)| n)
    }

    /// Constant functions fold when all their arguments are constant. Only `arg` depends
    /// on the primitive being evaluated.
    pub fn is_const(self) -> bool {
        self != Lib::Arg
    }

    /// The functions of one argument that are plain math.
    pub fn unary(self) -> Option<fn(f64) -> f64> {
        Some(match self {
            Lib::Floor => f64::floor,
            Lib::Ceil => f64::ceil,
            Lib::Sqrt => f64::sqrt,
            Lib::Exp => f64::exp,
            Lib::Log => f64::ln,
            Lib::Log10 => f64::log10,
            Lib::Sin => f64::sin,
            Lib::Cos => f64::cos,
            Lib::Tan => f64::tan,
            Lib::Asin => f64::asin,
            Lib::Acos => f64::acos,
            Lib::Atan => f64::atan,
            Lib::Rand => rand,
            Lib::Erf => libm::erf,
            Lib::Erfc => libm::erfc,
            _ => return None,
        })
    }
}

/// Radiance's deterministic `rand(x)`: a number in [0, 1) that jumps about with x.
#[allow(clippy::approx_constant)] // Radiance's constants, not e and π/4
pub fn rand(x: f64) -> f64 {
    let mut x = x * (1.0 / (1.0 + x * x) + 2.71828182845904);
    x += 0.785398163397447 - x.floor();
    x = 1e5 / x;
    x - x.floor()
}
