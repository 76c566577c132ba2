//! A pedestrian's state, as data: what it is doing ([`Activity`], one variant per behaviour state, carrying
//! what that state needs), where its crossing attempt stands ([`Attempt`]), and its phone-use plan
//! ([`Distraction`]). The labelled state of the paper's 12-state machine is [`Activity::label`].

use crate::sim::trace::PedState;

/// How a pedestrian moves across the road.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CrossMode {
    /// Steady crossing at base speed.
    CrossingRoad,
    /// Abrupt entry without checking.
    SuddenCrossing,
    /// Mid-block crossing.
    Jaywalking,
    /// Running because a vehicle approaches.
    RunningAcross,
}

impl CrossMode {
    fn label(self) -> PedState {
        match self {
            CrossMode::CrossingRoad => PedState::CrossingRoad,
            CrossMode::SuddenCrossing => PedState::SuddenCrossing,
            CrossMode::Jaywalking => PedState::Jaywalking,
            CrossMode::RunningAcross => PedState::RunningAcross,
        }
    }
}

/// Why a crossing pedestrian stands still on the road.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum PauseCause {
    /// A phone-use pause (distraction).
    Phone,
    /// A lookahead conflict with a vehicle; the lookahead has been clear for `clear_s` seconds.
    Conflict {
        /// Time the lookahead has been clear, seconds.
        clear_s: f64,
    },
}

/// What a sidewalk walker returns to after a phone-use episode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum AfterPhone {
    /// Walking on.
    WalkingSidewalk,
    /// Looking around at the curb (a crosser waiting to cross).
    LookingAround,
}

/// What a pedestrian is doing: one variant per behaviour state of the paper's machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Activity {
    /// Walking (or standing) on the sidewalk, AI mode.
    WalkingSidewalk,
    /// Scanning the surroundings.
    LookingAround,
    /// Assessing the traffic at the curb.
    CheckingTraffic,
    /// Decided, pausing at the curb before stepping out.
    Hesitating,
    /// On the road, moving across.
    Crossing(CrossMode),
    /// Stopped on the road; resumes `resume` afterwards.
    PausingMidCross {
        /// Why it stopped.
        cause: PauseCause,
        /// How it crosses on.
        resume: CrossMode,
    },
    /// Using a phone on the sidewalk.
    DistractedBehavior {
        /// What it returns to.
        resume: AfterPhone,
    },
    /// Reached the far sidewalk.
    FinishedCrossing,
    /// Walking back to the near curb.
    Retreat,
}

impl Activity {
    /// The labelled behaviour state.
    pub(crate) fn label(self) -> PedState {
        match self {
            Activity::WalkingSidewalk => PedState::WalkingSidewalk,
            Activity::LookingAround => PedState::LookingAround,
            Activity::CheckingTraffic => PedState::CheckingTraffic,
            Activity::Hesitating => PedState::Hesitating,
            Activity::Crossing(mode) => mode.label(),
            Activity::PausingMidCross { .. } => PedState::PausingMidCross,
            Activity::DistractedBehavior { .. } => PedState::DistractedBehavior,
            Activity::FinishedCrossing => PedState::FinishedCrossing,
            Activity::Retreat => PedState::Retreat,
        }
    }

    /// Whether the pedestrian holds a phone.
    pub(crate) fn on_phone(self) -> bool {
        matches!(
            self,
            Activity::DistractedBehavior { .. }
                | Activity::PausingMidCross {
                    cause: PauseCause::Phone,
                    ..
                }
        )
    }

    /// Whether the pedestrian moves under manual control along its crossing line (crossing states and retreat).
    pub(crate) fn crossing_motion(self) -> bool {
        self.label().is_crossing() || self == Activity::Retreat
    }
}

/// Where a pedestrian's crossing attempt stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Attempt {
    /// On the way to its curb point, or waiting there, not yet decided to cross.
    Undecided {
        /// Reached the curb point.
        at_curb: bool,
        /// Time waited at the curb, seconds (the patience cap counts this).
        waited_s: f64,
    },
    /// Decided to cross and not yet across.
    Committed {
        /// Reached (or returned to) the curb point.
        at_curb: bool,
        /// Committed while the ego approached inside the decision window (it then only waits for other
        /// vehicles about to arrive, and the ego brakes for it).
        window_commit: bool,
    },
    /// No crossing to attempt (any more): a non-crosser, a crosser that gave up, or one that crossed.
    Over {
        /// Whether it decided to cross (then crossed) before the attempt ended.
        decided: bool,
    },
}

impl Attempt {
    /// Whether the decision to cross has been taken.
    pub(crate) fn decided(self) -> bool {
        matches!(self, Attempt::Committed { .. } | Attempt::Over { decided: true })
    }

    /// Whether the attempt is over (finished, abandoned, or never planned).
    pub(crate) fn over(self) -> bool {
        matches!(self, Attempt::Over { .. })
    }

    /// Whether a crosser waits at its curb point (decided or not).
    pub(crate) fn at_curb(self) -> bool {
        match self {
            Attempt::Undecided { at_curb, .. } | Attempt::Committed { at_curb, .. } => at_curb,
            Attempt::Over { .. } => false,
        }
    }

    /// Marks the curb point as reached.
    pub(crate) fn reach_curb(&mut self) {
        if let Attempt::Undecided { at_curb, .. } | Attempt::Committed { at_curb, .. } = self {
            *at_curb = true;
        }
    }

    /// Decides to cross; returns whether this is a new decision.
    pub(crate) fn decide(&mut self) -> bool {
        match *self {
            Attempt::Undecided { at_curb, .. } => {
                *self = Attempt::Committed {
                    at_curb,
                    window_commit: false,
                };
                true
            }
            Attempt::Over { decided: false } => {
                *self = Attempt::Over { decided: true };
                true
            }
            Attempt::Committed { .. } | Attempt::Over { decided: true } => false,
        }
    }

    /// Ends the attempt (crossed or given up).
    pub(crate) fn end(&mut self) {
        *self = Attempt::Over {
            decided: self.decided(),
        };
    }
}

/// A pedestrian's phone-use plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Distraction {
    /// Never uses a phone.
    Never,
    /// Takes out a phone at this time into the clip, seconds.
    At(f64),
    /// Has had its phone-use episode.
    Done,
}
