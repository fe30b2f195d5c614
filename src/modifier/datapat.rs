//! Patterns, textures and mixtures over data files and pictures: `brightdata`,
//! `colordata`, `texdata`, `mixdata`, `colorpict`, `mixpict` (radiance-formats.md §2.3;
//! the files are read by [`super::data`] and [`super::picdata`]).
//!
//! ```text
//! mod brightdata id  f dfile ff x1..xN [xf]                 pattern ×= f(interp)
//! mod colordata  id  rf gf bf rfile gfile bfile ff x1..xN [xf]
//! mod colorpict  id  rf gf bf pic ff u v [xf]
//! mod texdata    id  fx fy fz xfile yfile zfile ff x1..xN [xf]
//! void mixdata   id  fore back f dfile ff x1..xN [xf]       foreground share f(interp)
//! void mixpict   id  fore back f pic ff u v [xf]            foreground share f(r, g, b)
//! ```
//! N is the data file's number of dimensions; the coordinates are expressions, the
//! functions are names (in the context of `ff`). With three values (r, g, b) the red
//! function gets all three, the green and blue functions their own value when they take
//! fewer than three parameters, else all three.

use super::data::DataArray;
use super::func::{compile, finite, function, load_context, FuncCall};
use super::picdata::PictData;
use super::{MixCoefficient, ModifierKind, ModifierLookup, Pattern, Texture};
use crate::cal::{EvalError, Evaluation, ExprId, FuncRef, LaneInputs, Program, Pure, LANES};
use crate::color::Color;
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use glam::DVec3;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Where the values come from.
#[derive(Debug)]
enum Source {
    /// One data file per value (1 or 3), all of the same dimensions.
    Data(Vec<Arc<DataArray>>),
    /// A picture: three values (r, g, b) at (u, v).
    Picture(Arc<PictData>),
}

/// The common part: values at coordinates, then functions of them.
#[derive(Debug)]
struct DataCall {
    call: FuncCall,
    source: Source,
    coords: Vec<ExprId>,
    funcs: Vec<FuncRef>,
    /// Whether later functions may take their own value (colour types) rather than all
    /// three (texdata).
    own_values: bool,
    /// The coordinates and functions as pure expressions, when all of them are
    /// (`crate::cal::Pure`; decided at the first evaluation, once the program is linked).
    pure: OnceLock<Option<PureCall>>,
}

/// A [`DataCall`]'s coordinates and functions as pure expressions.
#[derive(Debug)]
struct PureCall {
    /// One root per coordinate.
    coords: Pure,
    funcs: Vec<Pure>,
    /// Whether function `i` takes its own value (see [`DataCall::apply`]).
    own: Vec<bool>,
    /// The ray channels they read ([`crate::cal::Pure::channels_read`]).
    chans: u32,
    /// The same number for calls whose forms, arguments and number of values are the same
    /// ([`Pattern::shape`]): the luminaires of one ies2rad file placed many times.
    shape: usize,
}

/// The shapes met so far in this process, by their description ([`PureCall::shape`]),
/// and how many numbers were given beyond them.
static SHAPES: Mutex<Option<(HashMap<String, usize>, usize)>> = Mutex::new(None);

/// Most shapes remembered by description (a few kilobytes each); a call of a shape met
/// after them gets a number of its own, and is then computed alone.
const MAX_SHAPES: usize = 4096;

/// The number of the shape described by `key`.
fn shape_number(key: String) -> usize {
    let mut shapes = SHAPES.lock().unwrap_or_else(|e| e.into_inner());
    number_in(shapes.get_or_insert_with(|| (HashMap::new(), 0)), key)
}

/// The number of `key` in `(map, beyond)` ([`shape_number`]'s table).
fn number_in((map, beyond): &mut (HashMap<String, usize>, usize), key: String) -> usize {
    if let Some(&k) = map.get(&key) {
        return k;
    }
    if map.len() < MAX_SHAPES {
        let next = map.len();
        map.insert(key, next);
        return next;
    }
    *beyond += 1;
    MAX_SHAPES + *beyond
}

impl PureCall {
    fn new(prog: &Program, c: &DataCall) -> Option<PureCall> {
        // The primitive's own arguments, which every evaluation passes.
        let args = Some(c.call.args());
        let coords = prog.pure_exprs_with(&c.coords, args)?;
        let funcs = c
            .funcs
            .iter()
            .map(|f| prog.pure_func_with(*f, args))
            .collect::<Option<Vec<_>>>()?;
        let own = (0..c.funcs.len()).map(|i| c.takes_own(prog, i)).collect();
        let chans = funcs
            .iter()
            .fold(coords.channels_read(), |m, f| m | f.channels_read());
        // Everything an evaluation by these forms reads besides the lane's own frame and
        // data: the forms (their functions by address), the arguments, the values' count.
        let args: Vec<u64> = c.call.args().iter().map(|a| a.to_bits()).collect();
        let key = format!(
            "{coords:?} {funcs:?} {own:?} {chans} {args:?} {} {}",
            c.width(),
            matches!(c.source, Source::Picture(_))
        );
        Some(PureCall {
            coords,
            funcs,
            own,
            chans,
            shape: shape_number(key),
        })
    }
}

fn bad_count(p: &Primitive, need: usize) -> String {
    format!(
        "bad # arguments for {} \"{}\": {} string arguments, at least {need} needed",
        p.ptype,
        p.name,
        p.sargs.len()
    )
}

/// Parse `p`'s strings from `at`: `nf` function names, `nf` data files (or one picture),
/// the function file, the coordinates, the transform.
fn parse_call(
    p: &Primitive,
    l: &dyn ModifierLookup,
    at: usize,
    nf: usize,
    picture: bool,
) -> Result<DataCall, String> {
    let s = &p.sargs;
    let nfiles = if picture { 1 } else { nf };
    let ff_at = at + nf + nfiles;
    if s.len() <= ff_at {
        return Err(bad_count(p, ff_at + 1));
    }
    let files = l.files();
    let (source, ndims) = if picture {
        (Source::Picture(files.picture(&s[at + nf])?), 2)
    } else {
        let data = s[at + nf..ff_at]
            .iter()
            .map(|n| files.data(n))
            .collect::<Result<Vec<_>, _>>()?;
        let n = data[0].dims();
        if data.iter().any(|d| d.dims() != n) {
            return Err(format!(
                "{} \"{}\": data files of different dimensions",
                p.ptype, p.name
            ));
        }
        (Source::Data(data), n)
    };
    if s.len() < ff_at + 1 + ndims {
        return Err(bad_count(p, ff_at + 1 + ndims));
    }
    let fns = files.functions();
    let (funcs, coords) = fns.with(|b| {
        let ctx = load_context(b, &s[ff_at])?;
        let funcs = s[at..at + nf]
            .iter()
            .map(|n| function(b, n, ctx))
            .collect::<Result<Vec<_>, _>>()?;
        let coords = s[ff_at + 1..ff_at + 1 + ndims]
            .iter()
            .map(|t| compile(b, p, t, ctx))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((funcs, coords))
    })?;
    let call = FuncCall::new(fns.shared(), p, ff_at + 1 + ndims)?;
    Ok(DataCall {
        call,
        source,
        coords,
        funcs,
        own_values: true,
        pure: OnceLock::new(),
    })
}

impl DataCall {
    /// The values at the evaluated coordinates: one or three.
    fn values(&self, ev: &mut Evaluation) -> Result<[f64; 3], EvalError> {
        let mut x = [0.0; 6];
        for (xi, e) in x.iter_mut().zip(&self.coords) {
            *xi = finite(ev.eval(*e)?)?;
        }
        Ok(self.lookup(&x[..self.coords.len()]))
    }

    /// The values at coordinates `x`: one or three.
    fn lookup(&self, x: &[f64]) -> [f64; 3] {
        match &self.source {
            Source::Picture(p) => p.lookup(x[0], x[1]),
            Source::Data(d) => {
                let mut v = [0.0; 3];
                for (i, di) in d.iter().enumerate() {
                    // A file named again (one grey file for r, g and b) is read once per
                    // scene: its value here is the one just computed.
                    v[i] = match (0..i).find(|&k| Arc::ptr_eq(&d[k], di)) {
                        Some(k) => v[k],
                        None => di.interp(x),
                    };
                }
                v
            }
        }
    }

    /// Whether function `i` gets its own value rather than all of them: later functions
    /// of colour types that take fewer than three parameters.
    fn takes_own(&self, prog: &Program, i: usize) -> bool {
        i > 0 && self.own_values && prog.params(self.funcs[i]).is_some_and(|k| k < 3)
    }

    /// Function `i` of the values: the first (and a single value's) function gets them
    /// all, later ones their own when they take fewer than three parameters (colour
    /// types).
    fn apply(
        &self,
        ev: &mut Evaluation,
        i: usize,
        v: &[f64; 3],
        n: usize,
    ) -> Result<f64, EvalError> {
        let f = self.funcs[i];
        let own = self.takes_own(ev.program(), i);
        let r = if n == 1 || own {
            ev.call(f, &[v[i.min(n - 1)]])?
        } else {
            ev.call(f, &v[..n])?
        };
        finite(r)
    }

    /// Number of values per point.
    fn width(&self) -> usize {
        match &self.source {
            Source::Picture(_) => 3,
            Source::Data(d) => d.len(),
        }
    }

    /// The pure forms of the coordinates and the functions, made at their first use; None
    /// when they are not all pure.
    fn pure_call(&self) -> Option<&PureCall> {
        let prog = self.call.live_program()?;
        self.pure.get_or_init(|| PureCall::new(prog, self)).as_ref()
    }

    /// The functions' results by their pure forms: None when they are not all pure or an
    /// evaluation leaves its result to the machine.
    fn pure_results(&self, sp: &ShadingPoint) -> Option<[f64; 3]> {
        let pc = self.pure_call()?;
        self.pure_results_from(pc, &self.call.frame().channels_for(sp, pc.chans))
    }

    /// [`DataCall::pure_results`] from the ray channels `chan` (those `pc` reads).
    fn pure_results_from(&self, pc: &PureCall, chan: &[f64; 27]) -> Option<[f64; 3]> {
        let args = self.call.args();
        let mut x = [0.0; 6];
        let x = x.get_mut(..self.coords.len())?;
        pc.coords.eval_into(chan, args, &[], x)?;
        let v = self.lookup(x);
        let n = self.width();
        let mut out = [0.0; 3];
        for (i, o) in out.iter_mut().enumerate().take(pc.funcs.len()) {
            let vals = if n == 1 || pc.own[i] {
                std::slice::from_ref(&v[i.min(n - 1)])
            } else {
                &v[..n]
            };
            *o = pc.funcs[i].eval(chan, args, vals)?;
        }
        Some(out)
    }

    /// The functions' results (one per function): by their pure forms where they give
    /// them, else by the machine (the same values; errors only from the machine).
    fn results(&self, sp: &ShadingPoint) -> Option<[f64; 3]> {
        if let Some(r) = self.pure_results(sp) {
            return Some(r);
        }
        self.call.eval(sp, None, |ev| {
            let v = self.values(ev)?;
            let n = self.width();
            let mut out = [0.0; 3];
            for (i, o) in out.iter_mut().enumerate().take(self.funcs.len()) {
                *o = self.apply(ev, i, &v, n)?;
            }
            Ok(out)
        })
    }
}

/// A `brightdata`, `colordata` or `colorpict` pattern.
#[derive(Debug)]
pub struct DataPattern(DataCall);

impl DataPattern {
    fn colour_of(&self, r: [f64; 3]) -> Color {
        if self.0.funcs.len() == 1 {
            Color::splat(r[0])
        } else {
            Color::new(r[0], r[1], r[2])
        }
    }
}

impl Pattern for DataPattern {
    fn colour(&self, sp: &ShadingPoint) -> Option<Color> {
        let r = self.0.results(sp)?;
        Some(self.colour_of(r))
    }

    fn reads(&self) -> Option<u32> {
        self.0.pure_call().map(|pc| pc.chans)
    }

    fn as_data(&self) -> Option<&DataPattern> {
        Some(self)
    }
}

/// Data patterns of one shape ([`PureCall::shape`]: the luminaires of one ies2rad file
/// placed many times) at up to [`LANES`] points, whose colours are computed together by
/// their pure forms, evaluated for all lanes at once ([`Pure::eval_lanes`]): each lane's
/// colour is the one [`Pattern::colour`] gives it, from its own frame and data files. The
/// caller keeps the lanes' patterns (`pat(l)` of [`DataLanes::colours`]); a thread may keep
/// one of these for all its points.
pub struct DataLanes {
    n: usize,
    shape: usize,
    chans: [[f64; 27]; LANES],
}

impl Default for DataLanes {
    fn default() -> Self {
        DataLanes {
            n: 0,
            shape: 0,
            chans: [[0.0; 27]; LANES],
        }
    }
}

impl DataLanes {
    /// The shape pattern `p` would take a lane of, when it computes by pure forms.
    pub fn shape_of(p: &DataPattern) -> Option<usize> {
        p.0.pure_call().map(|pc| pc.shape)
    }

    /// Lanes taken.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether no lane is taken.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The shape of the lanes taken (None when there are none).
    pub fn shape(&self) -> Option<usize> {
        (self.n > 0).then_some(self.shape)
    }

    /// Take the next lane for pattern `p` at `sp`; false (none taken) when the lanes are
    /// full, of another shape, or `p` has no pure forms.
    pub fn push(&mut self, p: &DataPattern, sp: &ShadingPoint) -> bool {
        let Some(pc) = p.0.pure_call() else {
            return false;
        };
        if self.n == LANES || (self.n > 0 && pc.shape != self.shape) {
            return false;
        }
        self.shape = pc.shape;
        p.0.call
            .frame()
            .channels_into(sp, pc.chans, &mut self.chans[self.n]);
        self.n += 1;
        true
    }

    /// Empty the lanes.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// The lanes' colours: `out[l]` is Some(the colour, or None for a computation
    /// error) where the pure forms give it; None where the lane's pattern must be computed
    /// alone ([`Pattern::colour`]: the machine, which may report an error).
    pub fn colours<'p>(
        &self,
        pat: impl Fn(usize) -> &'p DataPattern,
        out: &mut [Option<Option<Color>>; LANES],
    ) {
        *out = [None; LANES];
        let n = self.n;
        if n == 0 {
            return;
        }
        let first = pat(0);
        let Some(pc) = first.0.pure_call() else {
            return;
        };
        if n == 1 {
            // One lane: as the pattern computes it alone, from the channels taken.
            if let Some(r) = first.0.pure_results_from(pc, &self.chans[0]) {
                out[0] = Some(Some(first.colour_of(r)));
            }
            return;
        }
        let call = &first.0;
        let ncoords = call.coords.len();
        let args = call.call.args();
        let none = [[0.0; 3]; LANES];
        let input = LaneInputs {
            chans: &self.chans,
            values: &none,
            nvalues: 0,
        };
        let mut x = [[0.0; 3]; LANES];
        let mut ok = [false; LANES];
        if ncoords > 3
            || !pc
                .coords
                .eval_lanes(n, &input, args, ncoords, &mut x, &mut ok)
        {
            return;
        }
        // Each lane's values from its own data.
        let mut v = [[0.0; 3]; LANES];
        for l in 0..n {
            if ok[l] {
                v[l] = pat(l).0.lookup(&x[l][..ncoords]);
            }
        }
        let width = call.width();
        let mut r = [[0.0; 3]; LANES];
        let mut vals = [[0.0; 3]; LANES];
        for (i, f) in pc.funcs.iter().enumerate() {
            let single = width == 1 || pc.own[i];
            for l in 0..n {
                vals[l] = match single {
                    true => [v[l][i.min(width - 1)], 0.0, 0.0],
                    false => v[l],
                };
            }
            let input = LaneInputs {
                chans: &self.chans,
                values: &vals,
                nvalues: if single { 1 } else { width },
            };
            let mut y = [[0.0; 3]; LANES];
            let mut fok = [false; LANES];
            if !f.eval_lanes(n, &input, args, 1, &mut y, &mut fok) {
                return;
            }
            for l in 0..n {
                r[l][i] = y[l][0];
                ok[l] &= fok[l];
            }
        }
        for l in 0..n {
            if ok[l] {
                out[l] = Some(Some(pat(l).colour_of(r[l])));
            }
        }
    }
}

#[derive(Debug)]
struct DataTexture(DataCall);

impl Texture for DataTexture {
    fn perturbation(&self, sp: &ShadingPoint) -> Option<DVec3> {
        let r = self.0.results(sp)?;
        Some(
            self.0
                .call
                .frame()
                .vector_to_world(sp, DVec3::from_array(r)),
        )
    }
}

#[derive(Debug)]
struct DataMix(DataCall);

impl MixCoefficient for DataMix {
    fn coefficient(&self, sp: &ShadingPoint) -> Option<f64> {
        self.0.results(sp).map(|r| r[0])
    }
}

/// Parser of `brightdata`.
pub fn parse_brightdata(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    Ok(ModifierKind::Pattern(Box::new(DataPattern(parse_call(
        p, l, 0, 1, false,
    )?))))
}

/// Parser of `colordata`.
pub fn parse_colordata(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    Ok(ModifierKind::Pattern(Box::new(DataPattern(parse_call(
        p, l, 0, 3, false,
    )?))))
}

/// Parser of `colorpict`.
pub fn parse_colorpict(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    Ok(ModifierKind::Pattern(Box::new(DataPattern(parse_call(
        p, l, 0, 3, true,
    )?))))
}

/// Parser of `texdata`: each function gets the three values.
pub fn parse_texdata(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let mut c = parse_call(p, l, 0, 3, false)?;
    c.own_values = false;
    Ok(ModifierKind::Texture(Box::new(DataTexture(c))))
}

/// Parser of `mixdata`.
pub fn parse_mixdata(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    Ok(ModifierKind::Mixture {
        coef: Box::new(DataMix(parse_call(p, l, 2, 1, false)?)),
        foreground: l.modref(&p.sargs[0])?,
        background: l.modref(&p.sargs[1])?,
    })
}

/// Parser of `mixpict`: the function gets (r, g, b).
pub fn parse_mixpict(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    Ok(ModifierKind::Mixture {
        coef: Box::new(DataMix(parse_call(p, l, 2, 1, true)?)),
        foreground: l.modref(&p.sargs[0])?,
        background: l.modref(&p.sargs[1])?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_numbered_once_and_bounded() {
        let mut table = (HashMap::new(), 0);
        let a = number_in(&mut table, "a".into());
        let b = number_in(&mut table, "b".into());
        assert_ne!(a, b);
        assert_eq!(number_in(&mut table, "a".into()), a);
        for k in 0..MAX_SHAPES {
            number_in(&mut table, format!("k{k}"));
        }
        assert_eq!(table.0.len(), MAX_SHAPES);
        // Beyond the bound each call gets a number of its own, never one in use.
        let (x, y) = (
            number_in(&mut table, "late".into()),
            number_in(&mut table, "late".into()),
        );
        assert!(x != y && x >= MAX_SHAPES && y >= MAX_SHAPES);
        assert_eq!(number_in(&mut table, "b".into()), b);
    }
}
