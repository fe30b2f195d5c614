//! `rad` input files (`.rif`): the variables of a Radiance project and the rpict options
//! `rad` derives from them (`docs/rif.md`).
//!
//! [`RadFile::read`] applies rad's syntax (one `NAME= value` per line, `#` comment lines,
//! backslash escapes and continuation lines, names matched case-sensitively by a prefix of
//! at least 3 characters, 2 for `PCMAP pfilt PGMAP UP view ZFILE ZONE`; upper-case
//! variables hold one value, the last assignment winning; lower-case ones collect their
//! values; every `view` line is a separate view). [`derive::RadPlan`] turns the variables
//! into rpict options the way `rad -n` prints them.

pub mod derive;
pub mod views;

use std::path::{Path, PathBuf};

/// The variables rad knows: name, shortest accepted prefix.
const VARIABLES: &[(&str, usize)] = &[
    ("AMBFILE", 3),
    ("DETAIL", 3),
    ("EXPOSURE", 3),
    ("EYESEP", 3),
    ("illum", 3),
    ("INDIRECT", 3),
    ("materials", 3),
    ("mkillum", 3),
    ("mkpmap", 3),
    ("objects", 3),
    ("oconv", 3),
    ("OCTREE", 3),
    ("OPTFILE", 3),
    ("PCMAP", 2),
    ("PENUMBRAS", 3),
    ("pfilt", 2),
    ("PGMAP", 2),
    ("PICTURE", 3),
    ("QUALITY", 3),
    ("RAWFILE", 3),
    ("render", 3),
    ("REPORT", 3),
    ("RESOLUTION", 3),
    ("rpict", 3),
    ("rvu", 3),
    ("scene", 3),
    ("UP", 2),
    ("VARIABILITY", 3),
    ("view", 2),
    ("ZFILE", 2),
    ("ZONE", 2),
];

/// A rif error: the file, the line (0 when not tied to one) and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {reason}", file.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
pub struct RifError {
    /// The rif file.
    pub file: PathBuf,
    /// 1-based line, 0 for the file as a whole.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// The full name of the variable `word` abbreviates, if any.
pub fn match_variable(word: &str) -> Option<&'static str> {
    VARIABLES
        .iter()
        .find(|(name, min)| word.len() >= *min && name.starts_with(word))
        .map(|(name, _)| *name)
}

/// The variables of a rif file (after command-line assignments).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RadFile {
    /// The file read.
    pub path: PathBuf,
    /// Single-valued and collected variables by full name, with the line that set them last.
    values: Vec<(&'static str, String, usize)>,
    /// The `view` assignments in order, with their lines.
    pub views: Vec<(String, usize)>,
    /// Warnings (repeated single-valued variables).
    pub warnings: Vec<String>,
}

impl RadFile {
    /// Read and parse a rif file.
    pub fn read(path: &Path) -> Result<RadFile, RifError> {
        let text = std::fs::read_to_string(path).map_err(|e| RifError {
            file: path.to_path_buf(),
            line: 0,
            reason: format!("cannot read: {e}"),
        })?;
        RadFile::parse(path, &text)
    }

    /// Parse rif text (`path` names it in errors).
    pub fn parse(path: &Path, text: &str) -> Result<RadFile, RifError> {
        let mut rf = RadFile {
            path: path.to_path_buf(),
            ..RadFile::default()
        };
        for (line, logical) in logical_lines(text) {
            rf.assign(&logical, line)?;
        }
        Ok(rf)
    }

    /// Apply one assignment (`NAME= value`; `=` optional), as a line of the file or a
    /// `VAR=value` given after it (line 0).
    pub fn assign(&mut self, text: &str, line: usize) -> Result<(), RifError> {
        let t = text.trim_start();
        if t.is_empty() || t.starts_with('#') {
            return Ok(());
        }
        let name_end = t
            .find(|c: char| c.is_whitespace() || c == '=')
            .unwrap_or(t.len());
        let word = &t[..name_end];
        let rest = t[name_end..].trim_start_matches(|c: char| c.is_whitespace() || c == '=');
        let name = match_variable(word).ok_or_else(|| RifError {
            file: self.path.clone(),
            line,
            reason: format!("unknown variable '{word}'"),
        })?;
        let value = squeeze(rest);
        if name == "view" {
            self.views.push((value, line));
            return Ok(());
        }
        let single = name.chars().next().is_some_and(|c| c.is_ascii_uppercase());
        match self.values.iter_mut().find(|(n, _, _)| *n == name) {
            Some(slot) if single => {
                self.warnings.push(format!(
                    "{}:{line}: {name} assigned again (the last value wins)",
                    self.path.display()
                ));
                slot.1 = value;
                slot.2 = line;
            }
            Some(slot) => {
                if !value.is_empty() {
                    if !slot.1.is_empty() {
                        slot.1.push(' ');
                    }
                    slot.1.push_str(&value);
                }
                slot.2 = line;
            }
            None => self.values.push((name, value, line)),
        }
        Ok(())
    }

    /// A variable's value (full name), None when not assigned or empty.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.values
            .iter()
            .find(|(n, v, _)| *n == name && !v.is_empty())
            .map(|(_, v, _)| v.as_str())
    }

    /// The line that last set a variable (0 if unset or set after the file).
    pub fn line_of(&self, name: &str) -> usize {
        self.values
            .iter()
            .find(|(n, _, _)| *n == name)
            .map_or(0, |(_, _, l)| *l)
    }

    /// An error about variable `name`, at the line that set it.
    pub fn error(&self, name: &str, reason: impl Into<String>) -> RifError {
        RifError {
            file: self.path.clone(),
            line: self.line_of(name),
            reason: reason.into(),
        }
    }

    /// The words of a variable's value (quotes kept together, without the quotes).
    pub fn words(&self, name: &str) -> Vec<String> {
        self.get(name).map(split_words).unwrap_or_default()
    }
}

/// Lines joined across backslash-newline, backslash escapes resolved (a quoted backslash
/// is kept), each with the number of its first physical line.
fn logical_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut start = 1;
    let mut line = 1;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' => match chars.next() {
                Some('\n') => {
                    line += 1;
                    cur.push(' ');
                }
                Some(n) => cur.push(n),
                None => {}
            },
            '\n' => {
                out.push((start, std::mem::take(&mut cur)));
                line += 1;
                start = line;
            }
            '\r' if chars.peek() == Some(&'\n') => {}
            c => cur.push(c),
        }
    }
    if !cur.trim().is_empty() {
        out.push((start, cur));
    }
    out
}

/// Whitespace squeezed to single spaces and trimmed, except inside quotes.
fn squeeze(s: &str) -> String {
    let mut out = String::new();
    let mut quote: Option<char> = None;
    let mut space = false;
    for c in s.trim().chars() {
        match quote {
            Some(q) => {
                out.push(c);
                if c == q {
                    quote = None;
                }
            }
            None if c.is_whitespace() => space = true,
            None => {
                if space && !out.is_empty() {
                    out.push(' ');
                }
                space = false;
                if c == '"' || c == '\'' {
                    quote = Some(c);
                }
                out.push(c);
            }
        }
    }
    out
}

/// Split a value into words; quoted parts stay one word, without their quotes.
pub fn split_words(s: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in s.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => cur.push(c),
            None if c == '"' || c == '\'' => {
                quote = Some(c);
                any = true;
            }
            None if c.is_whitespace() => {
                if any || !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
                any = false;
            }
            None => cur.push(c),
        }
    }
    if any || !cur.is_empty() {
        words.push(cur);
    }
    words
}

/// Read a rif file, apply `VAR=value` assignments after it, read its scene (with `extra`
/// scene files after its own) for the bounding cube, and derive rad's plan.
pub fn load(
    path: &Path,
    sets: &[String],
    extra: &[String],
    ro: &crate::scene::ReadOptions,
) -> anyhow::Result<derive::RadPlan> {
    let mut rf = RadFile::read(path)?;
    for s in sets {
        rf.assign(s, 0)?;
    }
    for w in &rf.warnings {
        eprintln!("warning: {w}");
    }
    let mut files: Vec<String> = rf
        .words("materials")
        .into_iter()
        .chain(rf.words("scene"))
        .chain(extra.iter().cloned())
        .collect();
    if files.is_empty() {
        anyhow::bail!(
            "{}: no scene files (set scene= and materials=, or give them after --)",
            path.display()
        );
    }
    // rad's octree cube is made of these; illum files join the octree later (`oconv -i`).
    let cube = scene_cube(&files, ro)?;
    let mut plan = derive::RadPlan::new(&rf, cube)?;
    files.extend(rf.words("illum"));
    plan.scene_files = std::mem::take(&mut files);
    Ok(plan)
}

/// The bounding cube of scene files (centre, size: the largest extent of the bounding box
/// of the finite surfaces), which rad takes for the default ZONE and for `-ar`.
pub fn scene_cube(
    files: &[String],
    ro: &crate::scene::ReadOptions,
) -> anyhow::Result<([f64; 3], f64)> {
    let prims = crate::scene::read_scene_files(files, ro)?;
    let build = crate::scene::ReadOptions {
        allow_commands: false,
        raypath: ro.raypath.clone(),
        ..crate::scene::ReadOptions::default()
    };
    let scene = crate::render::world::Scene::build_taking(prims, &build)?;
    let mut lo = glam::DVec3::splat(f64::INFINITY);
    let mut hi = glam::DVec3::splat(f64::NEG_INFINITY);
    for i in 0..scene.objects.len() {
        let (a, b) = scene.objects.surface(i).bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        anyhow::bail!(
            "{}: the scene has no surfaces to make a zone of",
            files.join(" ")
        );
    }
    let (lo, hi) = (lo + scene.origin, hi + scene.origin);
    let c = 0.5 * (lo + hi);
    Ok(([c.x, c.y, c.z], (hi - lo).max_element()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_by_prefix_and_case() {
        assert_eq!(match_variable("QUAL"), Some("QUALITY"));
        assert_eq!(match_variable("QU"), None);
        assert_eq!(match_variable("ZO"), Some("ZONE"));
        assert_eq!(match_variable("vi"), Some("view"));
        assert_eq!(match_variable("VIEW"), None);
        assert_eq!(match_variable("rpi"), Some("rpict"));
        assert_eq!(match_variable("res"), None);
        assert_eq!(match_variable("RES"), Some("RESOLUTION"));
        assert_eq!(match_variable("QUALITYX"), None);
    }

    #[test]
    fn values_collect_or_replace() {
        let rf = RadFile::parse(
            Path::new("t.rif"),
            "# c\nscene= a.rad\nsce b.rad \\\n  c.rad\nQUAL= L\nQUALITY=  H\nview= x\nview= -vp 1  2 3\nrender= -av '1  1' 1\n",
        )
        .unwrap();
        assert_eq!(rf.get("scene"), Some("a.rad b.rad c.rad"));
        assert_eq!(rf.get("QUALITY"), Some("H"));
        assert_eq!(rf.warnings.len(), 1);
        assert_eq!(rf.views.len(), 2);
        assert_eq!(rf.views[1].0, "-vp 1 2 3");
        assert_eq!(rf.words("render"), vec!["-av", "1  1", "1"]);
        let e = RadFile::parse(Path::new("t.rif"), "scene= a\nBOGUS= 1\n").unwrap_err();
        assert_eq!(e.to_string(), "t.rif:2: unknown variable 'BOGUS'");
    }
}
