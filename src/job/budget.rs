//! `-axt SECONDS START END` in a job: a per-frame time budget for frames that render in
//! parallel.
//!
//! Each frame's `-aa` is decided once, by the first worker to render one of its tiles, and
//! recorded in `JOB/budget/f<frame>.json`, written to a temporary and given its name without
//! replacing (of racing workers exactly one record wins; the others read it), so every tile
//! of the frame, whoever renders it and whenever, uses the same accuracy. The decision uses
//! the latest frame before it whose tiles are all done: that frame's `-aa` times
//! √(its CPU seconds summed over its tiles / SECONDS), within END..START, as `tpict -S` does
//! from the previous frame ([`TimeBudget::next`]). A frame that starts before any earlier
//! frame has finished (workers outnumbering a frame's tiles) gets START, or the latest
//! finished frame's decision. The record is validated when read: the job directory is
//! shared by many processes.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};

use super::manifest::Manifest;
use super::task::{self, TaskState};
use super::{tile, JobDir};
use crate::options::schedule::TimeBudget;

/// A frame's accuracy under `-axt`, as recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameBudget {
    /// The frame.
    pub frame: u32,
    /// Its `-aa`.
    pub aa: f64,
    /// The finished frame it was derived from (None: the first accuracy, START).
    pub from_frame: Option<u32>,
    /// That frame's `-aa`.
    pub from_aa: f64,
    /// That frame's CPU seconds (summed over its tiles).
    pub from_cpu_seconds: f64,
}

/// `JOB/budget/`.
pub fn budget_dir(job: &JobDir) -> PathBuf {
    job.root().join("budget")
}

fn record_path(job: &JobDir, frame: u32) -> PathBuf {
    budget_dir(job).join(format!("f{frame:05}.json"))
}

/// The recorded accuracy of `frame`, if decided. A damaged or implausible record is an error
/// naming the file (every tile of the frame must use the same accuracy, so it is not
/// silently replaced).
pub fn read(job: &JobDir, b: &TimeBudget, frame: u32) -> Result<Option<FrameBudget>> {
    let path = record_path(job, frame);
    let bytes = match crate::safefile::read_bounded(&path, 1 << 16) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(anyhow!("cannot read {}: {e}", path.display())),
    };
    let r: FrameBudget = serde_json::from_slice(&bytes)
        .with_context(|| format!("{}: not a frame budget record", path.display()))?;
    // The clamp in TimeBudget::next keeps aa within END..START; allow rounding.
    let tol = 1e-9 * b.start;
    if r.frame != frame
        || !r.aa.is_finite()
        || r.aa < b.end - tol
        || r.aa > b.start + tol
        || !r.from_aa.is_finite()
        || !r.from_cpu_seconds.is_finite()
    {
        bail!(
            "{}: damaged frame budget record (frame {} -aa {} for frame {frame}, -axt {} {} {})",
            path.display(),
            r.frame,
            r.aa,
            b.seconds,
            b.start,
            b.end
        );
    }
    Ok(Some(r))
}

/// The `-aa` of `frame` under the manifest's `-axt`: the recorded one, or decided now and
/// recorded (see the module notes).
pub fn frame_accuracy(job: &JobDir, m: &Manifest, frame: u32) -> Result<f64> {
    let b = m.params.axt.ok_or_else(|| anyhow!("the job has no -axt"))?;
    if let Some(r) = read(job, &b, frame)? {
        return Ok(r.aa);
    }
    let decision = decide(job, m, &b, frame)?;
    let dir = budget_dir(job);
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = record_path(job, frame);
    let json = serde_json::to_vec_pretty(&decision)?;
    match crate::image::output::write_atomic_noclobber(&path, |f| f.write_all(&json)) {
        Ok(()) => {
            super::sync_dir(&dir);
            Ok(decision.aa)
        }
        // Another worker decided first: its record holds.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => read(job, &b, frame)?
            .map(|r| r.aa)
            .ok_or_else(|| anyhow!("{} vanished after it was written", path.display())),
        Err(e) => Err(anyhow!("cannot write {}: {e}", path.display())),
    }
}

/// The decision for `frame`: from the latest earlier frame whose tiles are all done and
/// whose own accuracy is recorded, else START.
fn decide(job: &JobDir, m: &Manifest, b: &TimeBudget, frame: u32) -> Result<FrameBudget> {
    let states = task::scan(&job.tasks())
        .with_context(|| format!("cannot list {}", job.tasks().display()))?;
    let pieces = super::task::pieces(&states);
    let earlier = m.frames.iter().rev().filter(|f| f.index < frame);
    for fp in earlier {
        let done = (0..fp.tiles.len()).all(|i| {
            matches!(
                super::task::tile_state(&states, &pieces, fp.index, i),
                Some(TaskState::Done)
            )
        });
        if !done {
            continue;
        }
        let Some(prev) = read(job, b, fp.index)? else {
            continue;
        };
        let mut cpu = 0.0;
        let mut complete = true;
        let names = (0..fp.tiles.len()).flat_map(|i| super::task::task_names(&pieces, fp.index, i));
        for name in names {
            match tile::read(&job.tile_file(&name)) {
                Ok((meta, _)) if meta.cpu_seconds.is_finite() && meta.cpu_seconds >= 0.0 => {
                    cpu += meta.cpu_seconds
                }
                _ => complete = false,
            }
        }
        if !complete {
            continue;
        }
        return Ok(FrameBudget {
            frame,
            aa: b.next(prev.aa, cpu),
            from_frame: Some(fp.index),
            from_aa: prev.aa,
            from_cpu_seconds: cpu,
        });
    }
    Ok(FrameBudget {
        frame,
        aa: b.start,
        from_frame: None,
        from_aa: b.start,
        from_cpu_seconds: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_are_validated() {
        let t = tempfile::tempdir().unwrap();
        let job = JobDir::new(t.path());
        let b = TimeBudget::new(1.0, 0.4, 0.1).unwrap();
        assert!(read(&job, &b, 3).unwrap().is_none());
        std::fs::create_dir_all(budget_dir(&job)).unwrap();
        let good = FrameBudget {
            frame: 3,
            aa: 0.2,
            from_frame: Some(2),
            from_aa: 0.4,
            from_cpu_seconds: 4.0,
        };
        std::fs::write(record_path(&job, 3), serde_json::to_vec(&good).unwrap()).unwrap();
        assert_eq!(read(&job, &b, 3).unwrap(), Some(good.clone()));
        for bad in [
            FrameBudget {
                aa: 0.9,
                ..good.clone()
            },
            FrameBudget {
                aa: f64::NAN,
                ..good.clone()
            },
            FrameBudget {
                frame: 4,
                ..good.clone()
            },
        ] {
            let text = serde_json::to_string(&bad).unwrap().replace("NaN", "null");
            std::fs::write(record_path(&job, 3), text).unwrap();
            let e = read(&job, &b, 3).unwrap_err().to_string();
            assert!(e.contains("f00003.json"), "{e}");
        }
        std::fs::write(record_path(&job, 3), b"{\"frame\": 3, \"aa\"").unwrap();
        assert!(read(&job, &b, 3).is_err());
    }
}
