//! `pedestrians`: the population — counts per clip, the five archetypes (paper, Table "Character archetypes")
//! and their mix, the situational speed profiles.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{CountRange, Range};

/// The pedestrian population.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Pedestrians {
    /// Pedestrians per clip, `[min, max]`.
    pub per_clip: CountRange,
    /// Share of each archetype; must sum to 1. Replaced as a whole when given.
    pub archetype_mix: BTreeMap<String, f64>,
    /// Archetype parameters: the paper's five, overridable key by key, plus any new ones (which start from
    /// casual_person's parameters).
    pub archetypes: BTreeMap<String, Archetype>,
    /// Situational speed profiles.
    pub speed_profiles: SpeedProfiles,
    /// Gestures to the ego's driver.
    pub gestures: Gestures,
}

impl Default for Pedestrians {
    fn default() -> Self {
        let archetypes = Archetype::paper_table();
        Pedestrians {
            per_clip: CountRange(5, 10),
            archetype_mix: archetypes
                .iter()
                .map(|(name, (share, _))| (name.clone(), *share))
                .collect(),
            archetypes: archetypes.into_iter().map(|(name, (_, a))| (name, a)).collect(),
            speed_profiles: SpeedProfiles::default(),
            gestures: Gestures::default(),
        }
    }
}

/// Body model of an archetype.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Body {
    /// One adult.
    Adult,
    /// One child.
    Child,
    /// An adult walking with a child.
    AdultWithChild,
}

/// Behavioural parameters of a character archetype (paper, Table "Character archetypes").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Archetype {
    /// Base walking speed range, m/s.
    pub speed_mps: Range,
    /// Hesitation duration at the curb, seconds.
    pub hesitation_s: Range,
    /// Attention level 0–1: how often and how long the pedestrian scans traffic.
    pub attention: f64,
    /// Intrinsic crossing propensity 0–1 (the archetype check before a crossing).
    pub crossing_probability: f64,
    /// Gap-acceptance threshold τ_ttc, seconds (paper: 3–6 s by archetype).
    pub ttc_threshold_s: Range,
    /// Patience cap: longest wait at the curb before abandoning or crossing suddenly, seconds (paper: 6–18 s).
    pub patience_s: Range,
    /// Probability of distracted behaviour (phone use) during a clip.
    pub distraction_probability: f64,
    /// At a signalised crosswalk (traffic lights on): probability that the pedestrian crosses against the
    /// signal (on "don't walk", when its gap acceptance finds a gap) instead of waiting for "walk".
    pub red_light_violation_probability: f64,
    /// Body model.
    pub body: Body,
}

impl Default for Archetype {
    fn default() -> Self {
        Archetype::paper_table()
            .remove("casual_person")
            .map(|(_, a)| a)
            .unwrap_or(Archetype {
                speed_mps: Range(1.0, 1.4),
                hesitation_s: Range(0.5, 1.5),
                attention: 0.7,
                crossing_probability: 0.7,
                ttc_threshold_s: Range(4.0, 5.0),
                patience_s: Range(9.0, 13.0),
                distraction_probability: 0.15,
                red_light_violation_probability: 0.10,
                body: Body::Adult,
            })
    }
}

impl Archetype {
    /// The paper's five archetypes with their proportions. Speed, hesitation, attention and crossing
    /// probability are the paper's table; τ_ttc and patience spread the paper's ranges (3–6 s, 6–18 s) from
    /// risk-taking to cautious; distraction probabilities are pedsynth's choice. Red-light violation: 10.6 % of
    /// 1,707 crossings at signalised crossings were against the signal in Araya-Porras, Mora-Calderón and
    /// Aguero-Valverde (2022, Ingeniería 32(2), doi:10.15517/ri.v32i2.50386), and violations fall with age
    /// (Dommes et al. 2015, Accident Analysis and Prevention 80:67–75); the per-archetype rates are pedsynth's,
    /// ordered by age, and average 11 % over the default mix.
    pub fn paper_table() -> BTreeMap<String, (f64, Archetype)> {
        let row =
            |share, speed: (f64, f64), hes: (f64, f64), att, cross, ttc: (f64, f64), pat: (f64, f64), dis, body| {
                (
                    share,
                    Archetype {
                        speed_mps: Range(speed.0, speed.1),
                        hesitation_s: Range(hes.0, hes.1),
                        attention: att,
                        crossing_probability: cross,
                        ttc_threshold_s: Range(ttc.0, ttc.1),
                        patience_s: Range(pat.0, pat.1),
                        distraction_probability: dis,
                        red_light_violation_probability: 0.0,
                        body,
                    },
                )
            };
        let mut table = BTreeMap::from([
            (
                "business_person".to_owned(),
                row(
                    0.30,
                    (1.4, 1.8),
                    (0.3, 0.8),
                    0.5,
                    0.85,
                    (3.5, 4.5),
                    (7.0, 10.0),
                    0.20,
                    Body::Adult,
                ),
            ),
            (
                "casual_person".to_owned(),
                row(
                    0.25,
                    (1.0, 1.4),
                    (0.5, 1.5),
                    0.7,
                    0.70,
                    (4.0, 5.0),
                    (9.0, 13.0),
                    0.15,
                    Body::Adult,
                ),
            ),
            (
                "elderly_person".to_owned(),
                row(
                    0.10,
                    (0.6, 1.0),
                    (1.0, 2.0),
                    0.9,
                    0.50,
                    (5.0, 6.0),
                    (14.0, 18.0),
                    0.05,
                    Body::Adult,
                ),
            ),
            (
                "young_person".to_owned(),
                row(
                    0.20,
                    (1.2, 2.0),
                    (0.2, 0.6),
                    0.4,
                    0.90,
                    (3.0, 4.0),
                    (6.0, 9.0),
                    0.25,
                    Body::Adult,
                ),
            ),
            (
                "parent_with_child".to_owned(),
                row(
                    0.15,
                    (0.8, 1.2),
                    (0.8, 1.8),
                    0.8,
                    0.60,
                    (4.5, 5.5),
                    (11.0, 15.0),
                    0.10,
                    Body::AdultWithChild,
                ),
            ),
        ]);
        for (name, p) in [
            ("business_person", 0.12),
            ("casual_person", 0.10),
            ("elderly_person", 0.03),
            ("parent_with_child", 0.05),
            ("young_person", 0.20),
        ] {
            if let Some((_, a)) = table.get_mut(name) {
                a.red_light_violation_probability = p;
            }
        }
        table
    }
}

/// Gestures to the ego's driver (PIE's `gesture` labels). The paper lists gaze-based communication as future
/// work; these are pedsynth's. Each pedestrian gestures at most once per clip, decided by a draw that is a pure
/// function of the clip seed and the pedestrian (so gestures never shift any other random draw), and only when
/// the ego yields: it is ahead, within 30 m and slower than 3 m/s. A pedestrian on the phone does not gesture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Gestures {
    /// Probability that a crosser stepping out in front of a yielding ego acknowledges the driver (a raised
    /// hand, `hand_ack`, or a nod).
    pub acknowledge_probability: f64,
    /// Share of those acknowledgements that are a nod rather than a raised hand.
    pub nod_share: f64,
    /// Probability that a pedestrian at the curb who will not cross (a hard negative) waves a yielding ego on
    /// (`hand_yield`).
    pub wave_through_probability: f64,
}

impl Default for Gestures {
    fn default() -> Self {
        Gestures {
            acknowledge_probability: 0.3,
            nod_share: 0.3,
            wave_through_probability: 0.5,
        }
    }
}

/// Situational speed profiles (paper: cautious 0.8×, normal 1.0×, rushed 1.3×, distracted 0.9×).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SpeedProfiles {
    /// Share of pedestrians starting in each profile; must sum to 1.
    pub mix: SpeedProfileMix,
    /// Speed multiplier of each profile.
    pub multipliers: SpeedProfileMultipliers,
    /// Whether profiles switch during a clip (rushed when closing a tight gap, distracted on phone use).
    pub switching: bool,
}

impl Default for SpeedProfiles {
    fn default() -> Self {
        SpeedProfiles {
            mix: SpeedProfileMix {
                cautious: 0.2,
                normal: 0.4,
                rushed: 0.3,
                distracted: 0.1,
            },
            multipliers: SpeedProfileMultipliers {
                cautious: 0.8,
                normal: 1.0,
                rushed: 1.3,
                distracted: 0.9,
            },
            switching: true,
        }
    }
}

/// Shares of the four speed profiles (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpeedProfileMix {
    /// Share of cautious pedestrians.
    #[serde(default)]
    pub cautious: f64,
    /// Share of normal pedestrians.
    #[serde(default)]
    pub normal: f64,
    /// Share of rushed pedestrians.
    #[serde(default)]
    pub rushed: f64,
    /// Share of distracted pedestrians.
    #[serde(default)]
    pub distracted: f64,
}

/// Speed multipliers of the four profiles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SpeedProfileMultipliers {
    /// Cautious (poor visibility, elderly).
    pub cautious: f64,
    /// Normal.
    pub normal: f64,
    /// Rushed (closing a tight gap).
    pub rushed: f64,
    /// Distracted (phone use, with pauses).
    pub distracted: f64,
}

impl Default for SpeedProfileMultipliers {
    fn default() -> Self {
        SpeedProfiles::default().multipliers
    }
}

// ---------------------------------------------------------------------------------------------------------------
