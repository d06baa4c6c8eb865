//! Why [`LevenbergMarquardt`](super::LevenbergMarquardt) stopped, when it
//! stopped by its own tests (argmin adds its own reasons: `MaxItersReached`,
//! `TargetCostReached`, …).
//!
//! argmin carries a solver's reason as `TerminationReason::SolverExit(text)`;
//! the text is [`LmStop`]'s `Display`, and [`LmStop::from_reason`] reads it
//! back, so the words callers print and the typed reason cannot drift apart.

use argmin::core::TerminationReason;
use std::fmt;

/// A stop by one of the solver's own termination tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LmStop {
    /// The residual vector is exactly zero.
    ZeroResidual,
    /// The projected gradient passes the `gtol` test.
    Gtol,
    /// The relative cost reduction passes the `ftol` test.
    Ftol,
    /// The relative scaled step passes the `xtol` test.
    Xtol,
    /// The damping parameter grew past its maximum.
    StallDamping,
    /// Too many consecutive rejected steps.
    StallRejections,
}

impl LmStop {
    /// Every stop, in the order the tests run.
    pub const ALL: [LmStop; 6] = [
        LmStop::ZeroResidual,
        LmStop::Gtol,
        LmStop::Ftol,
        LmStop::Xtol,
        LmStop::StallDamping,
        LmStop::StallRejections,
    ];

    /// The text reported in `TerminationReason::SolverExit`.
    pub fn text(self) -> &'static str {
        match self {
            LmStop::ZeroResidual => "LM converged: residual is exactly zero",
            LmStop::Gtol => {
                "LM converged (gtol): projected gradient is orthogonal to the residual within gtol"
            }
            LmStop::Ftol => {
                "LM converged (ftol): actual and predicted relative cost reductions are below ftol"
            }
            LmStop::Xtol => "LM converged (xtol): relative scaled step length is below xtol",
            LmStop::StallDamping => {
                "LM stalled: damping parameter exceeded its maximum without an acceptable step"
            }
            LmStop::StallRejections => "LM stalled: too many consecutive rejected steps",
        }
    }

    /// Whether the run ended at a solution (the tolerance tests and the zero
    /// residual), not in a stall.
    pub fn is_converged(self) -> bool {
        !matches!(self, LmStop::StallDamping | LmStop::StallRejections)
    }

    /// The stop an argmin termination reason carries, if it is one of ours.
    pub fn from_reason(reason: &TerminationReason) -> Option<LmStop> {
        match reason {
            TerminationReason::SolverExit(s) => {
                LmStop::ALL.into_iter().find(|stop| stop.text() == s)
            }
            _ => None,
        }
    }
}

impl fmt::Display for LmStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.text())
    }
}

impl From<LmStop> for TerminationReason {
    fn from(stop: LmStop) -> Self {
        TerminationReason::SolverExit(stop.text().to_string())
    }
}
