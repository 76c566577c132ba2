//! `traffic`: vehicles per clip, driving profiles (CARLA Traffic Manager semantics), IDM constants, the ego
//! vehicle and emergency scenarios.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{CountRange, Range};

/// Traffic and the ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Traffic {
    /// Traffic vehicles per clip (besides the ego), `[min, max]`.
    pub vehicles_per_clip: CountRange,
    /// Share of each driving profile; must sum to 1.
    pub profile_mix: DrivingProfileMix,
    /// Parameters of each driving profile.
    pub profiles: DrivingProfiles,
    /// Intelligent Driver Model constants shared by all vehicles.
    pub idm: Idm,
    /// The ego vehicle.
    pub ego: Ego,
    /// Emergency scenarios (a vehicle braking hard or a pedestrian darting out close to the ego).
    pub emergency: Emergency,
    /// Traffic lights at the town's signalised junctions.
    pub signals: Signals,
    /// Cyclists: a third class of road user, riding at the right edge of the driving lanes.
    pub cyclists: Cyclists,
    /// Cars parked along the curbs: scenery that hides pedestrians, as on real streets.
    pub parked_cars: ParkedCars,
}

impl Default for Traffic {
    fn default() -> Self {
        Traffic {
            vehicles_per_clip: CountRange(5, 10),
            profile_mix: DrivingProfileMix {
                aggressive: 0.2,
                normal: 0.6,
                cautious: 0.2,
            },
            profiles: DrivingProfiles::default(),
            idm: Idm::default(),
            ego: Ego::default(),
            emergency: Emergency::default(),
            signals: Signals::default(),
            cyclists: Cyclists::default(),
            parked_cars: ParkedCars::default(),
        }
    }
}

/// Cars parked along the curbs, parallel to the road and facing its traffic, outside junctions and away from
/// crosswalks. They are scenery, as the parked cars CARLA's maps place are: semantic `Car` in the camera and
/// LiDAR streams, instance 0, no row in the `vehicles` table; the occlusion labels test against them. The
/// simulation does not steer around them, so a clip's parked cars stand only where none of its vehicles,
/// cyclists or pedestrians passes (each clip keeps the candidate places its traffic leaves free): on a street
/// with one lane each way they line the side that no vehicle of the clip drives along.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ParkedCars {
    /// Share of the candidate places along each curb (one every 7 m) that hold a car, drawn per clip and place
    /// from the clip's seed; 0 turns parked cars off. Default 0.4 (pedsynth's choice: every other car length
    /// or so, as on the residential streets of JAAD's videos).
    pub share: f64,
}

impl Default for ParkedCars {
    fn default() -> Self {
        ParkedCars { share: 0.4 }
    }
}

/// Cyclists: a bicycle with its rider, riding on the driving lanes near their right edge through junctions like
/// the vehicles (Intelligent Driver Model following, stopping at red lights where they run), braking for
/// pedestrians in their path and swerving around one at the lane's edge. Vehicles follow a cyclist and overtake
/// it with `overtaking_clearance_m` when the oncoming side is clear; pedestrians check cyclists in their gap
/// acceptance as they check cars. None by default (the paper's set-up has none).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Cyclists {
    /// Cyclists per clip, `[min, max]`. Default `[0, 0]`.
    pub per_clip: CountRange,
    /// Cruising speed, m/s `[min, max]` drawn per cyclist. Default 3.5–6.5 m/s (12.6–23.4 km/h: pedsynth's
    /// choice around the 15–20 km/h typical of urban commuting cyclists).
    pub speed_mps: Range,
    /// Distance from the right edge of the lane to the bicycle's centre line, metres. Default 0.8 (pedsynth's
    /// choice: clear of the curb, inside a 3 m lane).
    pub edge_offset_m: f64,
    /// Lateral clearance a vehicle keeps when it overtakes a cyclist, metres, side to side. Default 1.5 (the
    /// minimum passing distance in built-up areas in Germany's StVO § 5 (4) since 2020, France, Spain, ...).
    pub overtaking_clearance_m: f64,
    /// How far a cyclist swerves to the left around a pedestrian in its path at the lane's edge, metres (it
    /// brakes when that is not enough). Default 1.0.
    pub swerve_m: f64,
    /// Probability that a cyclist rides through red lights (where traffic lights run). Default 0.07 (Johnson et
    /// al. 2011, Accident Analysis & Prevention 43(1): 6.9 % of cyclists facing a red light in Melbourne rode
    /// through it).
    pub ignore_lights_probability: f64,
}

impl Default for Cyclists {
    fn default() -> Self {
        Cyclists {
            per_clip: CountRange(0, 0),
            speed_mps: Range(3.5, 6.5),
            edge_offset_m: 0.8,
            overtaking_clearance_m: 1.5,
            swerve_m: 1.0,
            ignore_lights_probability: 0.07,
        }
    }
}

/// Traffic lights: the heads of the town (an OpenDRIVE map's `<signal dynamic="yes">` records; built-in towns'
/// junctions of three or more approaches) run a fixed-time plan per junction, its phases green one after the
/// other as CARLA's traffic-light groups do (green, amber, then all red before the next phase), with a seeded
/// offset per junction and clip. Vehicles stop at red, and at amber when they can stop comfortably; a vehicle
/// drawn to ignore lights (its profile's `ignore_lights_probability`) drives through, and emergency vehicles
/// are allowed through.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Signals {
    /// Whether the lights run. Off by default (the paper's set-up has none). With them on the planner counts on
    /// the share of planned crossers seen crossing measured with lights (`calibration::crosser_realisation`:
    /// crossers wait for "walk" and the ego stops at red lights, so fewer are seen crossing).
    pub enabled: bool,
    /// Green time of each phase, seconds (CARLA's default: 10).
    pub green_s: f64,
    /// Amber (yellow) time after each green, seconds (CARLA's default: 3).
    pub amber_s: f64,
    /// All-red time after each amber, seconds (CARLA's default red time: 2).
    pub all_red_s: f64,
    /// Share of the crossers and hard negatives that start on a sidewalk placed at a signalised crosswalk: the
    /// first one on the ego's route within their spawn range, across the ego's approach road at the junction's
    /// mouth (where the route passes none, they are placed as usual). There they wait for "walk" (the ego's
    /// light is then red), unless their archetype's `red_light_violation_probability` draws them to cross
    /// against the signal.
    pub crosswalk_share: f64,
}

impl Default for Signals {
    fn default() -> Self {
        Signals {
            enabled: false,
            green_s: 10.0,
            amber_s: 3.0,
            all_red_s: 2.0,
            crosswalk_share: 0.5,
        }
    }
}

/// Shares of driving profiles (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DrivingProfileMix {
    /// Aggressive drivers.
    #[serde(default)]
    pub aggressive: f64,
    /// Normal drivers.
    #[serde(default)]
    pub normal: f64,
    /// Cautious drivers.
    #[serde(default)]
    pub cautious: f64,
}

/// The three driving profiles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DrivingProfiles {
    /// Aggressive: faster than the limit, short gaps, may ignore lights or pedestrians.
    pub aggressive: DrivingProfile,
    /// Normal.
    pub normal: DrivingProfile,
    /// Cautious: slower, long gaps.
    pub cautious: DrivingProfile,
}

impl Default for DrivingProfiles {
    fn default() -> Self {
        let p = |speed: (f64, f64), gap: (f64, f64), headway: (f64, f64), lights, walkers| DrivingProfile {
            speed_difference_pct: Range(speed.0, speed.1),
            min_gap_m: Range(gap.0, gap.1),
            time_headway_s: Range(headway.0, headway.1),
            ignore_lights_probability: lights,
            ignore_walkers_probability: walkers,
        };
        DrivingProfiles {
            aggressive: p((-30.0, -15.0), (0.5, 1.0), (0.8, 1.1), 0.2, 0.05),
            normal: p((-10.0, 10.0), (1.0, 2.0), (1.3, 1.7), 0.0, 0.0),
            cautious: p((10.0, 25.0), (2.0, 3.5), (1.9, 2.5), 0.0, 0.0),
        }
    }
}

/// One driving profile (CARLA Traffic Manager semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DrivingProfile {
    /// Percentage below the speed limit (negative: faster than the limit).
    pub speed_difference_pct: Range,
    /// IDM minimum gap s0 to the leader, metres.
    pub min_gap_m: Range,
    /// IDM desired time headway T, seconds.
    pub time_headway_s: Range,
    /// Probability that a vehicle of this profile ignores traffic lights.
    pub ignore_lights_probability: f64,
    /// Probability that a vehicle of this profile ignores pedestrians (it still records any contact).
    pub ignore_walkers_probability: f64,
}

impl Default for DrivingProfile {
    fn default() -> Self {
        DrivingProfiles::default().normal
    }
}

/// Intelligent Driver Model constants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Idm {
    /// Maximum acceleration a, m/s².
    pub max_accel_mps2: f64,
    /// Comfortable deceleration b, m/s².
    pub comfortable_decel_mps2: f64,
    /// Largest deceleration a vehicle can apply, m/s².
    pub max_decel_mps2: f64,
    /// Acceleration exponent δ.
    pub exponent: f64,
}

impl Default for Idm {
    fn default() -> Self {
        Idm {
            max_accel_mps2: 1.5,
            comfortable_decel_mps2: 3.0,
            max_decel_mps2: 8.0,
            exponent: 4.0,
        }
    }
}

/// The ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Ego {
    /// Percentage below the speed limit the ego drives at.
    pub speed_below_limit_pct: Range,
    /// Minimum gap to a leading vehicle, metres.
    pub min_gap_m: f64,
    /// The ego brakes for a crossing pedestrian closer than this ahead, metres.
    pub brake_ahead_m: f64,
    /// ... and within this lateral distance of its path, metres.
    pub brake_lateral_m: f64,
    /// Route length beyond what the clip needs, metres.
    pub route_margin_m: f64,
    /// Courtesy: for a pedestrian ahead that heads for the curb or waits there (looking, checking the traffic,
    /// hesitating), the ego eases off to this speed, m/s `[min, max]` drawn per clip, as drivers do when someone
    /// looks ready to cross. Crossers and hard negatives alike get it, so the ego's speed does not give the
    /// label away.
    pub courtesy_speed_mps: Range,
    /// ... for such pedestrians up to this far ahead along its route, metres.
    pub courtesy_ahead_m: f64,
    /// ... and this far to the side of its path, metres.
    pub courtesy_lateral_m: f64,
    /// For a pedestrian waiting at the curb attentively (looking, checking the traffic, hesitating) the ego stops
    /// this far short of its crossing point, front bumper to crossing, metres ...
    pub courtesy_stop_short_m: f64,
    /// ... and waits at most this long, seconds `[min, max]` drawn per clip; then it drives on at its eased speed
    /// (the pedestrian still may cross: the ego brakes for anyone crossing in its path).
    pub courtesy_patience_s: Range,
    /// For a crosser that waits for the ego to come near before it steps out
    /// (`crossing.scenario.crosser_ego_within_m`), the ego rolls up to within 0.7 of that distance (its front at
    /// least 2 m short of the pedestrian) instead of stopping `courtesy_stop_short_m` short, where the two would
    /// otherwise wait for each other: off by default.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub courtesy_roll_up: bool,
    /// The ego's heading about its path as a real car's wanders (lane-keeping corrections, the road's camber
    /// and curves a lane does not have): off by default.
    #[serde(skip_serializing_if = "super::is_default")]
    pub heading_wobble: Wobble,
    /// The ego's body pitch as a real car's nods (road undulation, joints and potholes, the suspension's answer
    /// to braking and throttle), about the ground point under its centre, nose up positive: off by default.
    /// Its camera and LiDAR pitch with it, so pedestrians' boxes move up and down together, as the boxes of
    /// pedestrians seen together in JAAD do (`pedsynth calibrate` fits it to them).
    #[serde(skip_serializing_if = "super::is_default")]
    pub pitch_wobble: Wobble,
}

/// A smooth offset of one of the ego's recorded angles (its heading: the stream `"ego heading"`; its body pitch:
/// `"ego pitch"`; so of its camera and LiDAR), drawn per clip from its seed: white noise through two first-order
/// lags of time constant `correlation_s`, stationary standard deviation `sd_deg`, so that the angle turns at a
/// smoothly changing rate as a steered, sprung car's does. The simulated path does not change, only where the
/// car (and its sensors) point along it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Wobble {
    /// Standard deviation of the heading offset, degrees (0: off).
    pub sd_deg: f64,
    /// Time constant of each of the two lags, seconds (autocorrelation `(1 + τ/T) e^(−τ/T)`).
    pub correlation_s: f64,
}

impl Default for Wobble {
    fn default() -> Self {
        Wobble {
            sd_deg: 0.0,
            correlation_s: 1.0,
        }
    }
}

impl Default for Ego {
    fn default() -> Self {
        Ego {
            speed_below_limit_pct: Range(15.0, 35.0),
            min_gap_m: 2.5,
            brake_ahead_m: 15.0,
            brake_lateral_m: 5.0,
            route_margin_m: 60.0,
            courtesy_speed_mps: Range(1.5, 3.5),
            courtesy_ahead_m: 35.0,
            courtesy_lateral_m: 10.0,
            courtesy_stop_short_m: 8.0,
            courtesy_patience_s: Range(5.0, 12.0),
            courtesy_roll_up: false,
            heading_wobble: Wobble::default(),
            pitch_wobble: Wobble::default(),
        }
    }
}

/// Emergency scenarios (the seed system's `--enable_emergency`): a share of the clips gets an oncoming
/// emergency vehicle with lights and siren on, faster than the limit; other vehicles stop for it and pedestrians
/// hold at the curb (those on the road hurry).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Emergency {
    /// Whether emergency scenarios are generated.
    pub enabled: bool,
    /// Share of the dataset's clips with an emergency vehicle (exact over the dataset; each town × weather
    /// stratum within one clip of its share).
    pub clip_share: f64,
    /// Share of each kind of emergency vehicle; must sum to 1.
    pub mix: EmergencyMix,
    /// How much faster than the speed limit an emergency vehicle drives, percent.
    pub speed_above_limit_pct: f64,
}

/// Shares of the three kinds of emergency vehicle (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EmergencyMix {
    /// Share of ambulances.
    #[serde(default)]
    pub ambulance: f64,
    /// Share of fire trucks.
    #[serde(default)]
    pub fire_truck: f64,
    /// Share of police cars.
    #[serde(default)]
    pub police: f64,
}

impl Default for Emergency {
    fn default() -> Self {
        Emergency {
            enabled: false,
            clip_share: 0.1,
            mix: EmergencyMix {
                ambulance: 0.4,
                fire_truck: 0.2,
                police: 0.4,
            },
            speed_above_limit_pct: 30.0,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
