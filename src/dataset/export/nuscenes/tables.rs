//! The records of nuScenes' JSON tables as `pedsynth export nuscenes` writes them (nuScenes' schema, with a few
//! keys of our own that the devkit ignores), the fixed vocabulary tables (`sensor`, `category`, `attribute`,
//! `visibility`) and the deterministic tokens.

use serde::Serialize;

/// A nuScenes token: 32 hex digits of the BLAKE3 hash of the record's identity (table and key parts), so that
/// the same dataset always exports the same tokens.
pub fn token(parts: &[&str]) -> String {
    let mut h = blake3::Hasher::new();
    for p in parts {
        h.update(p.as_bytes());
        h.update(&[0x1f]);
    }
    h.finalize().to_hex()[..32].to_owned()
}

/// `sensor.json` channels.
pub const CAM_FRONT: &str = "CAM_FRONT";
pub const LIDAR_TOP: &str = "LIDAR_TOP";

#[derive(Serialize)]
pub struct Sensor {
    pub token: String,
    pub channel: &'static str,
    pub modality: &'static str,
}

pub fn sensors() -> Vec<Sensor> {
    [(CAM_FRONT, "camera"), (LIDAR_TOP, "lidar")]
        .into_iter()
        .map(|(channel, modality)| Sensor {
            token: token(&["sensor", channel]),
            channel,
            modality,
        })
        .collect()
}

#[derive(Serialize)]
pub struct Category {
    pub token: String,
    pub name: &'static str,
    pub description: &'static str,
}

/// The nuScenes categories the export uses (nuScenes' names and descriptions).
pub const CATEGORIES: [(&str, &str); 7] = [
    ("human.pedestrian.adult", "Adult subcategory."),
    ("human.pedestrian.child", "Child subcategory."),
    (
        "vehicle.car",
        "Vehicle designed primarily for personal use, e.g. sedans, hatch-backs, wagons, vans, mini-vans, SUVs and \
         jeeps.",
    ),
    ("vehicle.emergency.ambulance", "All types of ambulances."),
    (
        "vehicle.emergency.police",
        "All types of police vehicles including police bicycles and motorcycles.",
    ),
    (
        "vehicle.truck",
        "Vehicles primarily designed to haul cargo including pick-ups, lorrys, trucks and semi-tractors. pedsynth's \
         fire trucks are exported here.",
    ),
    (
        "vehicle.bicycle",
        "Human or electric powered 2-wheeled vehicle designed to travel at lower speeds.",
    ),
];

pub fn categories() -> Vec<Category> {
    CATEGORIES
        .iter()
        .map(|&(name, description)| Category {
            token: token(&["category", name]),
            name,
            description,
        })
        .collect()
}

#[derive(Serialize)]
pub struct Attribute {
    pub token: String,
    pub name: &'static str,
    pub description: &'static str,
}

/// nuScenes' eight attributes, its names and descriptions.
pub const ATTRIBUTES: [(&str, &str); 8] = [
    ("vehicle.moving", "Vehicle is moving."),
    (
        "vehicle.stopped",
        "Vehicle, with a driver/rider in/on it, is currently stationary but has an intent to move.",
    ),
    (
        "vehicle.parked",
        "Vehicle is stationary (usually for longer duration) with no immediate intent to move.",
    ),
    ("cycle.with_rider", "There is a rider on the bicycle or motorcycle."),
    ("cycle.without_rider", "There is NO rider on the bicycle or motorcycle."),
    ("pedestrian.sitting_lying_down", "The human is sitting or lying down."),
    ("pedestrian.standing", "The human is standing."),
    ("pedestrian.moving", "The human is moving."),
];

pub fn attributes() -> Vec<Attribute> {
    ATTRIBUTES
        .iter()
        .map(|&(name, description)| Attribute {
            token: token(&["attribute", name]),
            name,
            description,
        })
        .collect()
}

#[derive(Serialize)]
pub struct Visibility {
    pub token: &'static str,
    pub level: &'static str,
    pub description: &'static str,
}

/// nuScenes' four visibility levels (tokens "1" to "4") and ours, "0", for boxes whose visibility the dataset
/// does not measure (traffic vehicles, and cyclists out of the camera's view).
pub fn visibilities() -> Vec<Visibility> {
    vec![
        Visibility {
            token: "0",
            level: "unknown",
            description: "visibility not measured: pedsynth has occlusion for pedestrians and for cyclists in the \
                          camera's view only",
        },
        Visibility {
            token: "1",
            level: "v0-40",
            description: "visibility of whole object is between 0 and 40%",
        },
        Visibility {
            token: "2",
            level: "v40-60",
            description: "visibility of whole object is between 40 and 60%",
        },
        Visibility {
            token: "3",
            level: "v60-80",
            description: "visibility of whole object is between 60 and 80%",
        },
        Visibility {
            token: "4",
            level: "v80-100",
            description: "visibility of whole object is between 80 and 100%",
        },
    ]
}

/// The visibility token of a share of the object hidden from the camera.
pub fn visibility_token(occlusion: Option<f32>) -> &'static str {
    match occlusion.map(|o| 1.0 - o) {
        None => "0",
        Some(v) if v < 0.4 => "1",
        Some(v) if v < 0.6 => "2",
        Some(v) if v < 0.8 => "3",
        Some(_) => "4",
    }
}

#[derive(Serialize)]
pub struct Log {
    pub token: String,
    pub logfile: String,
    pub vehicle: &'static str,
    pub date_captured: &'static str,
    pub location: String,
    // Ours.
    pub weather: String,
}

#[derive(Serialize)]
pub struct Map {
    pub token: String,
    pub log_tokens: Vec<String>,
    pub category: &'static str,
    pub filename: String,
    // Ours: the world position of the global frame's origin (global = world − world_origin_m).
    pub world_origin_m: [f64; 2],
}

#[derive(Serialize)]
pub struct Scene {
    pub token: String,
    pub log_token: String,
    pub nbr_samples: usize,
    pub first_sample_token: String,
    pub last_sample_token: String,
    pub name: String,
    pub description: String,
}

#[derive(Serialize)]
pub struct Sample {
    pub token: String,
    pub timestamp: u64,
    pub prev: String,
    pub next: String,
    pub scene_token: String,
}

#[derive(Serialize)]
pub struct SampleData {
    pub token: String,
    pub sample_token: String,
    pub ego_pose_token: String,
    pub calibrated_sensor_token: String,
    pub timestamp: u64,
    pub fileformat: &'static str,
    pub is_key_frame: bool,
    pub height: u32,
    pub width: u32,
    pub filename: String,
    pub prev: String,
    pub next: String,
}

#[derive(Serialize)]
pub struct EgoPose {
    pub token: String,
    pub timestamp: u64,
    pub rotation: [f64; 4],
    pub translation: [f64; 3],
}

#[derive(Serialize)]
pub struct CalibratedSensor {
    pub token: String,
    pub sensor_token: String,
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
    pub camera_intrinsic: Vec<[f64; 3]>,
}

#[derive(Serialize)]
pub struct Instance {
    pub token: String,
    pub category_token: String,
    pub nbr_annotations: usize,
    pub first_annotation_token: String,
    pub last_annotation_token: String,
    // Ours.
    pub clip_id: String,
    /// `pedestrian`, `vehicle` or `cyclist`.
    pub kind: &'static str,
    /// The pedestrian's, vehicle's or cyclist's id in the clip's tables.
    pub id: u32,
}

#[derive(Serialize)]
pub struct SampleAnnotation {
    pub token: String,
    pub sample_token: String,
    pub instance_token: String,
    pub visibility_token: &'static str,
    pub attribute_tokens: Vec<String>,
    pub translation: [f64; 3],
    /// Width, length, height (nuScenes' order), metres.
    pub size: [f64; 3],
    pub rotation: [f64; 4],
    pub prev: String,
    pub next: String,
    pub num_lidar_pts: u32,
    pub num_radar_pts: u32,
    // Ours (pedestrians only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crossing: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub behaviour_state: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tte_frames: Option<Option<u32>>,
}
