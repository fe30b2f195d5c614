//! Radiance's option syntax at the level of words: splitting option files into words,
//! `@file` and `$VAR` expansion, booleans (`-i`, `-i+`, `-iT`), numbers (finite, integers,
//! ranges) and the errors of every option parser (tpict's command line, view files and
//! lines, job manifests' options).
//!
//! Parsing rules follow rpict: booleans toggle when bare and accept `+ 1 y Y t T` / `- 0 n N
//! f F` suffixes; numbers must be finite.

/// rpict's and rtrace's option names, for the suggestion of an unknown option.
const KNOWN: &[&str] = &[
    "-vtv", "-vtl", "-vtc", "-vth", "-vta", "-vts", "-vp", "-vd", "-vu", "-vh", "-vv", "-vo",
    "-va", "-vs", "-vl", "-vf", "-x", "-y", "-pa", "-pj", "-ps", "-pt", "-pm", "-pd", "-dt", "-dc",
    "-dj", "-ds", "-dr", "-dp", "-dv", "-ss", "-st", "-lr", "-lw", "-av", "-aw", "-ab", "-aa",
    "-ar", "-ad", "-as", "-ae", "-ai", "-aE", "-aI", "-af", "-me", "-ma", "-mg", "-ms", "-i", "-u",
    "-bv", "-w", "-t", "-e", "-o", "-S", "-n", "-h", "-I", "-ld",
];

/// ` (did you mean -ab? 'tpict -help' lists every option)` for an unknown option one edit
/// away from a known one, else the pointer to the list.
fn suggest(w: &str) -> String {
    let close = KNOWN.iter().find(|k| edit_distance(k, w) == 1);
    match close {
        Some(k) => format!(" (did you mean {k}? -defaults lists every option)"),
        None => " (-defaults lists every option)".to_string(),
    }
}

/// Levenshtein distance of two short words.
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    if a.len().abs_diff(b.len()) > 2 || b.len() > 64 {
        return usize::MAX;
    }
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Errors from option parsing, view validation and view files.
#[derive(Debug, thiserror::Error)]
pub enum OptError {
    /// An option's argument is not a valid number.
    #[error("option {option}: expected {expected}, got '{got}'")]
    BadNumber {
        /// The option, e.g. `-vp`.
        option: String,
        /// What was expected, e.g. `3 numbers`.
        expected: String,
        /// The offending word.
        got: String,
    },
    /// An option is missing some of its arguments.
    #[error(
        "option {option}: expected {expected}, got only {got} before the end of the arguments"
    )]
    MissingArgument {
        /// The option.
        option: String,
        /// What was expected.
        expected: String,
        /// How many arguments were found.
        got: usize,
    },
    /// A value that parses but is out of range or otherwise wrong.
    #[error("option {option}: {reason}")]
    BadValue {
        /// The option.
        option: String,
        /// Why the value is rejected.
        reason: String,
    },
    /// An option nobody knows.
    #[error("unknown option {0}{hint}", hint = suggest(.0))]
    Unknown(String),
    /// A Radiance option that tpict does not implement.
    #[error("option {option} is not supported: {reason}")]
    Unsupported {
        /// The option.
        option: String,
        /// Why, or what to do instead.
        reason: String,
    },
    /// Options and scene files out of order.
    #[error(
        "option {option} after scene file '{scene}': options must come before the scene files"
    )]
    OptionAfterScene {
        /// The misplaced option.
        option: String,
        /// The scene file before it.
        scene: String,
    },
    /// A view that `setview` rejects.
    #[error("invalid view: {0}")]
    InvalidView(String),
    /// A problem at a line of a file.
    #[error("{path}:{line}: {reason}")]
    File {
        /// File name.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A view file without any view line.
    #[error("{0}: no view found")]
    NoView(String),
    /// A file that cannot be read.
    #[error("cannot read {path}: {reason}")]
    Io {
        /// File name.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// `@file` or `$VAR` expansion failure.
    #[error("argument expansion: {0}")]
    Expand(String),
}

/// Parse a finite floating-point argument of `option` (which takes `n` numbers).
pub fn parse_f64(option: &str, word: &str, n: usize) -> Result<f64, OptError> {
    match word.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && !word.trim().is_empty() => Ok(v),
        _ => Err(OptError::BadNumber {
            option: option.to_string(),
            expected: if n == 1 {
                "a number".to_string()
            } else {
                format!("{n} numbers")
            },
            got: word.to_string(),
        }),
    }
}

/// Parse an integer argument of `option`.
pub(crate) fn parse_int<T: std::str::FromStr>(option: &str, word: &str) -> Result<T, OptError> {
    word.trim().parse::<T>().map_err(|_| OptError::BadNumber {
        option: option.to_string(),
        expected: "an integer".to_string(),
        got: word.to_string(),
    })
}

/// The argument `i` of the option at `words[0]`, or an error saying `expected`.
pub(crate) fn arg<'a>(
    words: &'a [String],
    i: usize,
    expected: &str,
) -> Result<&'a String, OptError> {
    words.get(i).ok_or_else(|| OptError::MissingArgument {
        option: words[0].clone(),
        expected: expected.to_string(),
        got: i - 1,
    })
}

/// The option's one number.
pub(crate) fn f1(words: &[String]) -> Result<f64, OptError> {
    parse_f64(&words[0], arg(words, 1, "a number")?, 1)
}

/// The option's three numbers.
pub(crate) fn f3(words: &[String]) -> Result<[f64; 3], OptError> {
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        *o = parse_f64(&words[0], arg(words, k + 1, "3 numbers")?, 3)?;
    }
    Ok(out)
}

/// The option's one integer.
pub(crate) fn i1<T: std::str::FromStr>(words: &[String]) -> Result<T, OptError> {
    parse_int(&words[0], arg(words, 1, "an integer")?)
}

/// `v` if within `lo..=hi`, else an error naming the option.
pub(crate) fn range(option: &str, v: f64, lo: f64, hi: f64) -> Result<f64, OptError> {
    if v < lo || v > hi {
        let what = if hi == f64::INFINITY {
            format!("value {v} must be at least {lo}")
        } else {
            format!("value {v} out of range {lo}..{hi}")
        };
        return Err(OptError::BadValue {
            option: option.to_string(),
            reason: what,
        });
    }
    Ok(v)
}

/// `v` if not negative.
pub(crate) fn nonneg_i32(option: &str, v: i32) -> Result<i32, OptError> {
    if v < 0 {
        return Err(OptError::BadValue {
            option: option.to_string(),
            reason: format!("value {v} must not be negative"),
        });
    }
    Ok(v)
}

/// `v` if no component is negative.
pub(crate) fn nonneg3(option: &str, v: [f64; 3]) -> Result<[f64; 3], OptError> {
    for c in v {
        range(option, c, 0.0, f64::INFINITY)?;
    }
    Ok(v)
}

/// The error for a Radiance option Tessera does not implement.
pub(crate) fn unsupported(option: &str, reason: &str) -> OptError {
    OptError::Unsupported {
        option: option.to_string(),
        reason: reason.to_string(),
    }
}

/// Boolean option: `word` is `-name` (toggle) or `-name` plus one of `+ 1 y Y t T` (true) or
/// `- 0 n N f F` (false). Returns `None` if `word` is not this option.
pub fn bool_option(word: &str, name: &str, current: bool) -> Option<bool> {
    let rest = word.strip_prefix('-')?.strip_prefix(name)?;
    match rest {
        "" => Some(!current),
        "+" | "1" | "y" | "Y" | "t" | "T" => Some(true),
        "-" | "0" | "n" | "N" | "f" | "F" => Some(false),
        _ => None,
    }
}

/// Split text into words like Radiance's option files: whitespace separates words, double or
/// single quotes group (and are removed), `#` at the start of a word comments out the rest of
/// the line.
pub fn split_words(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut chars = text.chars().peekable();
    loop {
        while chars.peek().is_some_and(|c| c.is_whitespace()) {
            chars.next();
        }
        let Some(&c) = chars.peek() else { break };
        if c == '#' {
            for c in chars.by_ref() {
                if c == '\n' {
                    break;
                }
            }
            continue;
        }
        let mut w = String::new();
        while let Some(&c) = chars.peek() {
            if c.is_whitespace() {
                break;
            }
            chars.next();
            if c == '"' || c == '\'' {
                for q in chars.by_ref() {
                    if q == c {
                        break;
                    }
                    w.push(q);
                }
            } else {
                w.push(c);
            }
        }
        out.push(w);
    }
    out
}

/// Maximum nesting of `@file` inclusions.
const MAX_EXPAND_DEPTH: usize = 32;

/// Expand `@file` (the words of a file; quotes and `#` comments handled like Radiance's
/// option files; nested `@` allowed up to a depth limit; error naming the file if it is
/// missing) and `$VAR` words (the variable's value split into words; error if unset).
pub fn expand_args(args: &[String]) -> Result<Vec<String>, OptError> {
    let mut out = Vec::with_capacity(args.len());
    expand_into(args, 0, &mut out)?;
    Ok(out)
}

fn expand_into(args: &[String], depth: usize, out: &mut Vec<String>) -> Result<(), OptError> {
    if depth > MAX_EXPAND_DEPTH {
        return Err(OptError::Expand(format!(
            "@file nesting deeper than {MAX_EXPAND_DEPTH} (recursive inclusion?)"
        )));
    }
    for a in args {
        if let Some(file) = a.strip_prefix('@').filter(|f| !f.is_empty()) {
            let text = std::fs::read(file).map_err(|e| OptError::Io {
                path: file.to_string(),
                reason: e.to_string(),
            })?;
            let words = split_words(&String::from_utf8_lossy(&text));
            expand_into(&words, depth + 1, out)?;
        } else if let Some(var) = a.strip_prefix('$').filter(|v| !v.is_empty()) {
            match std::env::var(var) {
                Ok(val) => expand_into(&split_words(&val), depth + 1, out)?,
                Err(_) => {
                    return Err(OptError::Expand(format!(
                        "environment variable '{var}' is not set"
                    )))
                }
            }
        } else {
            out.push(a.clone());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn booleans() {
        assert_eq!(bool_option("-i", "i", false), Some(true));
        assert_eq!(bool_option("-i", "i", true), Some(false));
        assert_eq!(bool_option("-iT", "i", false), Some(true));
        assert_eq!(bool_option("-bvf", "bv", true), Some(false));
        assert_eq!(bool_option("-ix", "i", false), None);
        assert_eq!(bool_option("-ab", "i", false), None);
    }

    #[test]
    fn split_words_quotes_comments() {
        assert_eq!(
            split_words("-ab 2 # bounces\n\"a b\" 'c d'e\n#x y\n-i"),
            vec!["-ab", "2", "a b", "c de", "-i"]
        );
    }
}
