//! Ambient accuracy that varies with time (`-ax`, `-axg`): the seed paper's "time varying
//! accuracy" (§4.1). An animation's first frames use a large `-aa` (few, widely spaced
//! ambient values) and later frames tighten it toward the final accuracy, reusing the values
//! of earlier frames, so the cost of the ambient calculation is spread over several frames
//! instead of falling on the first one (docs/animation.md).

/// How `-aa` changes from frame to frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AccuracySchedule {
    /// `-aa` of the first frame.
    pub start: f64,
    /// `-aa` reached at the end and kept.
    pub end: f64,
    /// `-ax`: subtracted at each frame; `-axg`: the factor each frame multiplies by.
    pub step: f64,
    /// `-axg`: a geometric schedule (large steps at low accuracy, small ones near the end).
    pub geometric: bool,
}

impl AccuracySchedule {
    /// Parse `-ax start end step` (`geometric` false) or `-axg start end ratio`.
    pub fn new(start: f64, end: f64, step: f64, geometric: bool) -> Result<Self, String> {
        let finite = [start, end, step].iter().all(|v| v.is_finite());
        if !finite || end <= 0.0 || start < end {
            return Err(format!(
                "needs start >= end > 0 (got {start} {end}): accuracy starts relaxed and \
                 tightens toward the final -aa"
            ));
        }
        if geometric && !(step > 0.0 && step < 1.0) {
            return Err(format!("ratio {step} must be between 0 and 1"));
        }
        if !geometric && step <= 0.0 {
            return Err(format!("step {step} must be positive"));
        }
        Ok(AccuracySchedule {
            start,
            end,
            step,
            geometric,
        })
    }

    /// `-aa` for the frame at `position` (0 for the animation's first frame).
    pub fn accuracy(&self, position: u32) -> f64 {
        let k = position as f64;
        let aa = if self.geometric {
            self.start * self.step.powf(k)
        } else {
            self.start - self.step * k
        };
        aa.max(self.end)
    }

    /// The first frame at the final accuracy.
    pub fn frames_to_final(&self) -> u32 {
        let mut k = 0u32;
        while self.accuracy(k) > self.end && k < u32::MAX {
            k += 1;
        }
        k
    }

    /// The option as words (`-ax s e step` or `-axg s e ratio`).
    pub fn to_words(&self) -> Vec<String> {
        vec![
            if self.geometric { "-axg" } else { "-ax" }.to_string(),
            format!("{}", self.start),
            format!("{}", self.end),
            format!("{}", self.step),
        ]
    }
}

/// `-axt SECONDS START END`: a per-frame time budget (tpict's view sequences). The first
/// frame renders at `-aa START`; after each frame the accuracy for the next is scaled by
/// √(frame CPU seconds / SECONDS), within END..START, since the cost of new ambient values
/// goes about as 1/aa²: frames that took too long relax the next, cheap frames tighten it
/// toward END.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TimeBudget {
    /// CPU seconds per frame aimed at.
    pub seconds: f64,
    /// `-aa` of the first frame, and the loosest allowed.
    pub start: f64,
    /// The tightest `-aa`.
    pub end: f64,
}

impl TimeBudget {
    /// Check `-axt SECONDS START END`.
    pub fn new(seconds: f64, start: f64, end: f64) -> Result<Self, String> {
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(format!(
                "budget {seconds} must be a positive number of seconds"
            ));
        }
        if !(start.is_finite() && end.is_finite() && end > 0.0 && start >= end) {
            return Err(format!("needs start >= end > 0 (got {start} {end})"));
        }
        Ok(TimeBudget {
            seconds,
            start,
            end,
        })
    }

    /// The accuracy after a frame rendered at `aa` cost `cost` CPU seconds.
    pub fn next(&self, aa: f64, cost: f64) -> f64 {
        if !(cost.is_finite() && cost > 0.0) {
            return aa;
        }
        (aa * (cost / self.seconds).sqrt()).clamp(self.end, self.start)
    }

    /// The option as words.
    pub fn to_words(&self) -> Vec<String> {
        vec![
            "-axt".to_string(),
            format!("{}", self.seconds),
            format!("{}", self.start),
            format!("{}", self.end),
        ]
    }
}

/// `-axm RELAX AHEAD`: moving-direction accuracy (the seed paper's §4.2, proposed there and
/// not built): a region of frame k whose surfaces are no longer seen from frame k+AHEAD's
/// view renders with `-aa` times RELAX; regions that stay in view keep the frame's `-aa`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotionAccuracy {
    /// The factor on `-aa` for regions about to leave the view (> 1).
    pub relax: f64,
    /// How many frames ahead to look.
    pub ahead: u32,
}

impl MotionAccuracy {
    /// Check `-axm RELAX AHEAD`.
    pub fn new(relax: f64, ahead: f64) -> Result<Self, String> {
        if !(1.0..=100.0).contains(&relax) {
            return Err(format!("factor {relax} must be between 1 and 100"));
        }
        if !((1.0..=10_000.0).contains(&ahead) && ahead.fract() == 0.0) {
            return Err(format!(
                "frames ahead {ahead} must be a whole number from 1"
            ));
        }
        Ok(MotionAccuracy {
            relax,
            ahead: ahead as u32,
        })
    }

    /// Share of a region's sample points still seen `ahead` frames later below which the
    /// region counts as leaving the view.
    pub const STAYING: f64 = 0.5;

    /// The option as words.
    pub fn to_words(&self) -> Vec<String> {
        vec![
            "-axm".to_string(),
            format!("{}", self.relax),
            format!("{}", self.ahead),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_schedule() {
        // The seed paper's art gallery: -ax 0.575 0.125 0.0075 reaches 0.125 at frame 60
        // (frame 61 counted from 1).
        let s = AccuracySchedule::new(0.575, 0.125, 0.0075, false).unwrap();
        assert_eq!(s.accuracy(0), 0.575);
        assert!((s.accuracy(30) - 0.35).abs() < 1e-12);
        assert_eq!(s.frames_to_final(), 60);
        assert_eq!(s.accuracy(1000), 0.125);
    }

    #[test]
    fn budgets_relax_slow_frames_and_tighten_fast_ones() {
        let b = TimeBudget::new(2.0, 0.4, 0.1).unwrap();
        assert_eq!(b.next(0.2, 8.0), 0.4); // 4x over: 0.2*2 = 0.4
        assert!((b.next(0.2, 0.5) - 0.1).abs() < 1e-12); // 4x under: 0.1
        assert_eq!(b.next(0.2, 0.02), 0.1); // clamped at END
        assert_eq!(b.next(0.2, f64::NAN), 0.2);
        assert!(TimeBudget::new(0.0, 0.4, 0.1).is_err());
        assert!(TimeBudget::new(1.0, 0.1, 0.4).is_err());
    }

    #[test]
    fn geometric_steps_shrink() {
        let s = AccuracySchedule::new(0.6, 0.1, 0.8, true).unwrap();
        let steps: Vec<f64> = (0..8).map(|k| s.accuracy(k) - s.accuracy(k + 1)).collect();
        assert!(steps.windows(2).all(|w| w[0] >= w[1]));
        assert_eq!(s.frames_to_final(), 9); // 0.6·0.8^9 = 0.081 < 0.1 ≤ 0.6·0.8^8
        assert!(AccuracySchedule::new(0.1, 0.2, 0.01, false).is_err());
        assert!(AccuracySchedule::new(0.3, 0.0, 0.01, false).is_err());
        assert!(AccuracySchedule::new(0.3, 0.1, 1.5, true).is_err());
        assert!(AccuracySchedule::new(0.3, 0.1, -1.0, false).is_err());
        assert!(AccuracySchedule::new(f64::NAN, 0.1, 0.1, false).is_err());
    }
}
