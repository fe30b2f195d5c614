//! The run parameters: how one tpict process runs and where its output goes, none of which
//! changes a pixel: progress reports (`-t`), warnings (`-w`), threads (`-n`), the output file
//! (`-o`), view sequences (`-S`), the error file (`-e`), inline commands
//! (`--allow-commands`), the most primitives a scene may expand to (`--max-primitives`), the
//! default modifier of `.obj` scene files (`--obj-material`, which
//! changes only what is read: a job keeps it in its flattened scene), statistics (`--stats`) and the ambient stores (`-af`, `--amb-log`,
//! `--amb-flush`, `--amb-force`). Not kept in job manifests.

use super::words::{arg, bool_option, f1, i1, range, unsupported, OptError};

/// How a tpict run goes about its work.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunParams {
    /// `-t` seconds between progress reports (0: none).
    pub report_interval: f64,
    /// `-w` warnings.
    pub warnings: bool,
    /// `-n N` threads (None: default, resolved by the caller).
    pub threads: Option<usize>,
    /// `-o` output file (pattern with `%d` for `-S`).
    pub output: Option<String>,
    /// `-S n` read views from stdin, frames numbered from n.
    pub sequence_start: Option<u32>,
    /// `-e file` error file.
    pub error_file: Option<String>,
    /// `--allow-commands`: allow `!command` lines in scene files.
    pub allow_commands: bool,
    /// `--stats FILE`: write render statistics.
    pub stats_file: Option<String>,
    /// `--obj-material NAME`: the modifier of `.obj` scene files' triangles that have no
    /// modifier name or an undefined one.
    pub obj_material: Option<String>,
    /// `-af` Radiance ambient file (read at the start, this run's values appended at the end).
    pub amb_file: Option<String>,
    /// `--amb-log FILE`: Tessera's append-only ambient log (shared between processes).
    pub amb_log: Option<String>,
    /// `--amb-flush N`: append new ambient values to the log every N values.
    pub amb_flush: usize,
    /// `--amb-force`: use an ambient log whose fingerprint does not match.
    pub amb_force: bool,
    /// `--max-primitives N`: most primitives the scene may expand to (None: the default,
    /// [`crate::scene::reader::DEFAULT_MAX_PRIMITIVES`]).
    #[serde(default)]
    pub max_primitives: Option<usize>,
}

impl Default for RunParams {
    /// rpict's defaults.
    fn default() -> Self {
        RunParams {
            report_interval: 0.0,
            warnings: true,
            threads: None,
            output: None,
            sequence_start: None,
            error_file: None,
            allow_commands: false,
            stats_file: None,
            obj_material: None,
            amb_file: None,
            amb_log: None,
            amb_flush: 128,
            amb_force: false,
            max_primitives: None,
        }
    }
}

impl RunParams {
    /// Try to apply one run option at `words[0]`. Returns `Ok(Some(n_words_consumed))` if it
    /// was a run option, `Ok(None)` if not.
    pub fn apply_option(&mut self, words: &[String]) -> Result<Option<usize>, OptError> {
        let Some(w) = words.first() else {
            return Ok(None);
        };
        let w = w.as_str();
        if let Some(b) = bool_option(w, "w", self.warnings) {
            self.warnings = b;
            return Ok(Some(1));
        }
        let n = match w {
            "-t" => {
                self.report_interval = range(w, f1(words)?, 0.0, f64::INFINITY)?;
                2
            }
            "-n" => {
                let v: usize = i1(words)?;
                if v == 0 {
                    return Err(OptError::BadValue {
                        option: w.into(),
                        reason: "thread count must be at least 1".into(),
                    });
                }
                self.threads = Some(v);
                2
            }
            "-o" => {
                self.output = Some(arg(words, 1, "a file name")?.clone());
                2
            }
            "-S" => {
                self.sequence_start = Some(i1(words)?);
                2
            }
            "-e" => {
                let a = arg(words, 1, "a file name")?;
                if a.contains('=') || a.contains(':') {
                    return Err(unsupported(
                        w,
                        &format!(
                            "'{a}' is a function-file expression; only -e errfile is supported"
                        ),
                    ));
                }
                self.error_file = Some(a.clone());
                2
            }
            "-af" => {
                self.amb_file = Some(arg(words, 1, "a file name")?.clone());
                2
            }
            "--allow-commands" => {
                self.allow_commands = true;
                1
            }
            "--obj-material" => {
                self.obj_material = Some(arg(words, 1, "a modifier name")?.clone());
                2
            }
            "--stats" => {
                self.stats_file = Some(arg(words, 1, "a file name")?.clone());
                2
            }
            "--amb-log" => {
                self.amb_log = Some(arg(words, 1, "a file name")?.clone());
                2
            }
            "--amb-flush" => {
                let v = arg(words, 1, "a count")?;
                self.amb_flush = match v.parse::<usize>() {
                    Ok(n) if n > 0 => n,
                    _ => {
                        return Err(OptError::BadValue {
                            option: w.to_string(),
                            reason: format!("expected a positive count, got '{v}'"),
                        })
                    }
                };
                2
            }
            "--amb-force" => {
                self.amb_force = true;
                1
            }
            "--max-primitives" => {
                let v = arg(words, 1, "a count")?;
                self.max_primitives = match v.parse::<usize>() {
                    Ok(n) if n > 0 => Some(n),
                    _ => {
                        return Err(OptError::BadValue {
                            option: w.to_string(),
                            reason: format!("expected a positive count, got '{v}'"),
                        })
                    }
                };
                2
            }
            _ => return Ok(None),
        };
        Ok(Some(n))
    }

    /// The parameters as option words that [`RunParams::apply_option`] reads back.
    pub fn to_words(&self) -> Vec<String> {
        let mut w: Vec<String> = vec![
            "-t".into(),
            self.report_interval.to_string(),
            if self.warnings { "-w+" } else { "-w-" }.into(),
        ];
        if let Some(n) = self.threads {
            w.extend(["-n".into(), n.to_string()]);
        }
        if let Some(o) = &self.output {
            w.extend(["-o".into(), o.clone()]);
        }
        if let Some(n) = self.sequence_start {
            w.extend(["-S".into(), n.to_string()]);
        }
        if let Some(e) = &self.error_file {
            w.extend(["-e".into(), e.clone()]);
        }
        if let Some(af) = &self.amb_file {
            w.extend(["-af".into(), af.clone()]);
        }
        if self.allow_commands {
            w.push("--allow-commands".into());
        }
        if let Some(m) = &self.obj_material {
            w.extend(["--obj-material".into(), m.clone()]);
        }
        if let Some(n) = self.max_primitives {
            w.extend(["--max-primitives".into(), n.to_string()]);
        }
        if let Some(f) = &self.stats_file {
            w.extend(["--stats".into(), f.clone()]);
        }
        if let Some(f) = &self.amb_log {
            w.extend(["--amb-log".into(), f.clone()]);
        }
        if self.amb_flush != 128 {
            w.extend(["--amb-flush".into(), self.amb_flush.to_string()]);
        }
        if self.amb_force {
            w.push("--amb-force".into());
        }
        w
    }
}
