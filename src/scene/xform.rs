//! Built-in `xform`: the command-line layer around [`Transform`].
//!
//! `xform [-c] [-e] [-I] [-n prefix] [-m modifier] transforms... [-a N transforms...]... files...`
//! Behaviour follows real xform 6.0a (checked against it):
//! - `-n pre` renames surfaces (and instances/meshes) to `pre.name`; materials, patterns and
//!   other non-surfaces keep their names. `-m mod` likewise replaces only surfaces' modifiers.
//! - `-a N` makes N copies; the transforms after it (up to the next `-a`) are applied k times
//!   in copy k (it becomes `-i k`). Copies are named `pre.k` with `-n pre`, else `ak`; nested
//!   arrays give `pre.j.k` / `aj.k` with the last index varying fastest.
//! - `-i n` repeats the group of transforms that follows it n times.
//! - `-I` turns surfaces inside out (see [`Transform::with_invert`]).
//! - `-c` and `-e` are accepted and ignored (everything is expanded anyway).
//! - at least one file must be named (reading stdin makes no sense inline).

use super::primitive::Primitive;
use super::transform::{
    appended_words, is_surface, parse_groups, parse_transform, Group, Transform, TransformState,
};

/// One copy produced by an xform command.
#[derive(Clone, Debug, PartialEq)]
pub struct XformCopy {
    /// Name prefix for surfaces (`pre`, `pre.0`, `a1.2`...), if any.
    pub prefix: Option<String>,
    /// The transform of this copy (with `-I` applied).
    pub transform: Transform,
}

/// A parsed xform command line.
#[derive(Clone, Debug, PartialEq)]
pub struct XformCommand {
    /// Replacement modifier for surfaces (`-m`).
    pub modifier: Option<String>,
    /// The copies (one unless `-a` is used).
    pub copies: Vec<XformCopy>,
    /// The files to read, in order.
    pub files: Vec<String>,
}

/// Why xform arguments were not accepted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum XformArgError {
    /// Valid for real xform but not built in (run the real program if allowed).
    Unsupported(String),
    /// Invalid arguments.
    Bad(String),
}

/// Upper bound on the number of array copies, to keep bad input from exhausting memory.
const MAX_COPIES: u64 = 1_000_000;

/// Parse the arguments after the word `xform`.
pub fn parse_xform_args(args: &[String]) -> Result<XformCommand, XformArgError> {
    parse_xform(args, false)
}

/// Parse the arguments of an `xform` that reads its standard input (a later stage of a
/// pipeline): no file may be named (`-` alone stands for standard input).
pub fn parse_xform_stdin_args(args: &[String]) -> Result<XformCommand, XformArgError> {
    let mut c = parse_xform(args, true)?;
    match c.files.as_slice() {
        [] => Ok(c),
        [f] if f == "-" => {
            c.files.clear();
            Ok(c)
        }
        _ => Err(XformArgError::Bad(
            "xform: a pipeline stage reads standard input; it cannot also name files".to_string(),
        )),
    }
}

fn parse_xform(args: &[String], stdin: bool) -> Result<XformCommand, XformArgError> {
    let bad = |s: String| XformArgError::Bad(format!("xform: {s}"));
    let mut prefix: Option<String> = None;
    let mut modifier = None;
    let mut invert = false;
    // Transform words, with "-a N" kept as (index into words, count).
    let mut words: Vec<String> = Vec::new();
    let mut arrays: Vec<(usize, u64)> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        let w = args[i].as_str();
        match w {
            "-c" | "-e" => i += 1,
            "-I" => {
                invert = true;
                i += 1;
            }
            "-n" | "-m" => {
                let v = args
                    .get(i + 1)
                    .ok_or_else(|| bad(format!("missing argument for {w}")))?;
                if w == "-n" {
                    prefix = Some(v.clone());
                } else {
                    modifier = Some(v.clone());
                }
                i += 2;
            }
            "-a" => {
                let v = args
                    .get(i + 1)
                    .ok_or_else(|| bad("missing argument for -a".to_string()))?;
                let n: u64 = v
                    .parse()
                    .map_err(|_| bad(format!("bad array count '{v}' for -a")))?;
                arrays.push((words.len(), n));
                words.push("-a".to_string());
                words.push(v.clone());
                i += 2;
            }
            _ => {
                let (_, used) = parse_transform(&args[i..]).map_err(bad)?;
                if used == 0 {
                    if w.starts_with('-') && w.len() > 1 {
                        return Err(XformArgError::Unsupported(format!(
                            "xform option '{w}' is not built in"
                        )));
                    }
                    break;
                }
                words.extend(args[i..i + used].iter().cloned());
                i += used;
            }
        }
    }
    let files: Vec<String> = args[i..].to_vec();
    if files.is_empty() && !stdin {
        return Err(bad(
            "no file named (xform reading standard input is not allowed inline)".to_string(),
        ));
    }
    let total: u64 = arrays
        .iter()
        .try_fold(1u64, |acc, &(_, n)| {
            acc.checked_mul(n).filter(|&t| t <= MAX_COPIES)
        })
        .ok_or_else(|| bad(format!("array too large (more than {MAX_COPIES} copies)")))?;
    // The transform's repeat groups, each array's "-a N" standing as the "-i k" of its copy:
    // the copies are built incrementally (a copy's group takes one more application than
    // the previous copy's), so N copies cost N group applications, not N²/2.
    let mut template = words.clone();
    for &(pos, _) in &arrays {
        template[pos] = "-i".to_string();
        template[pos + 1] = "1".to_string();
    }
    let (groups, used) = parse_groups(&template).map_err(bad)?;
    if used != template.len() {
        return Err(bad(format!("bad transform word '{}'", template[used])));
    }
    // The group each array's "-i" opens: one more than the "-i"s before it.
    let array_group: Vec<usize> = arrays
        .iter()
        .map(|&(pos, _)| 1 + template[..pos].iter().filter(|w| *w == "-i").count())
        .collect();
    let mut copies = Vec::with_capacity(total as usize);
    let mut idx = vec![0u64; arrays.len()];
    let ctx = Arrays {
        groups: &groups,
        array_group: &array_group,
        counts: arrays.iter().map(|a| a.1).collect(),
        positions: arrays.iter().map(|a| a.0).collect(),
        words: &words,
        prefix: &prefix,
        invert,
    };
    ctx.build(0, 0, TransformState::default(), &mut idx, &mut copies);
    Ok(XformCommand {
        modifier,
        copies,
        files,
    })
}

/// What the copies of an array transform are built from.
struct Arrays<'a> {
    groups: &'a [Group],
    /// The group of each array.
    array_group: &'a [usize],
    /// Each array's copy count and the position of its "-a" in `words`.
    counts: Vec<u64>,
    positions: Vec<usize>,
    words: &'a [String],
    prefix: &'a Option<String>,
    invert: bool,
}

impl Arrays<'_> {
    /// Apply the groups from `g` on to `state`; at array `k`'s group, branch into its copies
    /// (the last array varies fastest), each from the previous one with one more
    /// application.
    fn build(
        &self,
        g: usize,
        k: usize,
        mut state: TransformState,
        idx: &mut Vec<u64>,
        out: &mut Vec<XformCopy>,
    ) {
        let mut g = g;
        while g < self.groups.len() {
            if k < self.array_group.len() && self.array_group[k] == g {
                let group = &self.groups[g];
                for j in 0..self.counts[k] {
                    if j > 0 {
                        state.apply(group);
                    }
                    idx[k] = j;
                    self.build(g + 1, k + 1, state, idx, out);
                }
                return;
            }
            state.apply_group(&self.groups[g]);
            g += 1;
        }
        out.push(self.copy(state, idx));
    }

    /// The copy of indices `idx` with the transform `state`.
    fn copy(&self, state: TransformState, idx: &[u64]) -> XformCopy {
        let mut ew = self.words.to_vec();
        for (k, &pos) in self.positions.iter().enumerate() {
            ew[pos] = "-i".to_string();
            ew[pos + 1] = idx[k].to_string();
        }
        let ids: Vec<String> = idx.iter().map(|k| k.to_string()).collect();
        let prefix = match (self.prefix, self.positions.is_empty()) {
            (p, true) => p.clone(),
            (Some(p), false) => Some(format!("{p}.{}", ids.join("."))),
            (None, false) => Some(format!("a{}", ids.join("."))),
        };
        XformCopy {
            prefix,
            transform: state.finish(appended_words(&ew)).with_invert(self.invert),
        }
    }
}

impl XformCommand {
    /// Apply one copy (transform, `-n` renaming and `-m` modifier) to a primitive.
    pub fn apply(&self, copy: &XformCopy, p: &Primitive) -> Result<Primitive, String> {
        let mut q = copy.transform.apply(p)?;
        if is_surface(&p.ptype) {
            if let Some(pre) = &copy.prefix {
                q.name = format!("{pre}.{}", q.name);
            }
            if let Some(m) = &self.modifier {
                q.modifier = m.clone();
            }
        }
        Ok(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn arrays_and_names() {
        let c =
            parse_xform_args(&a("-n pre -a 2 -t 1 0 0 -a 3 -t 0 1 0 -i 2 -rx 3 f.rad")).unwrap();
        assert_eq!(c.copies.len(), 6);
        assert_eq!(c.copies[1].prefix.as_deref(), Some("pre.0.1"));
        assert_eq!(
            c.copies[5].transform.words(),
            &a("-i 1 -t 1 0 0 -i 2 -t 0 1 0 -i 2 -rx 3")[..]
        );
        let c = parse_xform_args(&a("-t 1 0 0 -a 2 -rz 90 f g")).unwrap();
        assert_eq!(c.copies[1].prefix.as_deref(), Some("a1"));
        assert_eq!(c.files, a("f g"));
        assert_eq!(
            c.copies[0].transform.words(),
            &a("-i 1 -t 1 0 0 -i 0 -rz 90")[..]
        );
    }

    /// `-a N` copies are built incrementally: about one group application per copy (it was
    /// N²/2: 100k copies took over a minute), each copy's matrix bit-identical to parsing
    /// its own words afresh.
    #[test]
    fn arrays_are_linear_and_exact() {
        use crate::scene::transform::APPLICATIONS;
        let cmd = parse_xform_args(&a(
            "-n p -t 1 2 3 -a 7 -rz 13 -t .5 0 0 -s 1.1 -a 5 -t 0 0 1 -rx 7 -i 2 -ry 3 f.rad",
        ))
        .unwrap();
        assert_eq!(cmd.copies.len(), 35);
        for c in &cmd.copies {
            let (fresh, _) = parse_transform(c.transform.words()).unwrap();
            assert_eq!(fresh.matrix(), c.transform.matrix(), "{:?}", c.prefix);
            assert_eq!(fresh.scale(), c.transform.scale());
            assert_eq!(fresh.mirrors(), c.transform.mirrors());
        }
        assert_eq!(cmd.copies[8].prefix.as_deref(), Some("p.1.3"));
        let n = 100_000u64;
        APPLICATIONS.with(|c| c.set(0));
        let big = parse_xform_args(&a(&format!("-t 1 0 0 -a {n} -t 2 0 0 -rz 1 f.rad"))).unwrap();
        let applied = APPLICATIONS.with(|c| c.get());
        assert_eq!(big.copies.len() as u64, n);
        assert!(
            applied <= 3 * n,
            "{applied} group applications for {n} copies"
        );
        let last = big.copies.last().unwrap().transform.matrix();
        let (fresh, _) = parse_transform(big.copies.last().unwrap().transform.words()).unwrap();
        assert_eq!(fresh.matrix(), last);
    }

    #[test]
    fn errors() {
        assert!(matches!(
            parse_xform_args(&a("-t 1 2 3")),
            Err(XformArgError::Bad(_))
        ));
        assert!(matches!(
            parse_xform_args(&a("-t 1 2 x f")),
            Err(XformArgError::Bad(_))
        ));
        assert!(matches!(
            parse_xform_args(&a("-a x f")),
            Err(XformArgError::Bad(_))
        ));
        assert!(matches!(
            parse_xform_args(&a("-f args f")),
            Err(XformArgError::Unsupported(_))
        ));
        assert!(matches!(
            parse_xform_args(&a("-a 100000 -a 100000 -t 1 0 0 f")),
            Err(XformArgError::Bad(_))
        ));
    }
}
