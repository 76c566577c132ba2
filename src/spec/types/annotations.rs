//! `annotations`, `output` and `limits`: which pedestrians are annotated and how labels are derived, output
//! encodings and compression, and the sanity limits on a dataset's size.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::Range;

/// Annotation rules.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Annotations {
    /// The visibility gate: which pedestrians are annotated in a frame.
    pub visibility: Visibility,
    /// A pedestrian keeps C=1 for this many frames after briefly leaving a driving lane (label smoothing).
    pub crossing_label_smoothing_frames: u32,
    /// Keypoint format of the `keypoints` and `keypoints_3d` columns.
    pub pose_format: PoseFormat,
    /// A pedestrian is `look`ing at the ego when its gaze (the head's forward direction) is within this angle
    /// of the direction from its eyes to the camera, degrees.
    pub look_cone_deg: f64,
    /// The `annotator_*` box beside the tight one: drawn as a person draws it.
    pub annotator_box: AnnotatorBox,
    /// The box the exports (`pie`, `jaad`, `pab-poses`, `pab-poses-jaad`, `seed-csv`, `openscenario`) and
    /// `pedsynth calibrate --compare` read: `tight` (the silhouette's, the default) or `annotator`.
    pub export_box: ExportBox,
}

impl Default for Annotations {
    fn default() -> Self {
        Annotations {
            visibility: Visibility::default(),
            crossing_label_smoothing_frames: 5,
            pose_format: PoseFormat::Coco17,
            look_cone_deg: 30.0,
            annotator_box: AnnotatorBox::default(),
            export_box: ExportBox::Tight,
        }
    }
}

/// Which 2D box a consumer of the tables reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ExportBox {
    /// The tight box of the projected body (`bbox_*`).
    #[default]
    Tight,
    /// The annotator box (`annotator_*`).
    Annotator,
}

/// How the annotator box is drawn from the tight box: hand-drawn boxes in JAAD and PIE are looser than a
/// silhouette (wider than a walking person's legs and arms), sit on whole pixels and move a little from frame to
/// frame. Per pedestrian, a margin and a narrowest aspect are drawn from the ranges; per frame, each edge gets
/// Gaussian noise; the box keeps the tight box's centre and stays in the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct AnnotatorBox {
    /// Margin added around the silhouette, as a fraction of the tight box's height, `[min, max]` (drawn per
    /// pedestrian; half above, half below, and the same width on each side).
    pub margin_frac: Range,
    /// The narrowest box, width / height, `[min, max]` (drawn per pedestrian): a narrower silhouette gets a
    /// box this wide (plus `width_pad_px`).
    pub min_aspect: Range,
    /// Pixels added to the narrowest box's width, `min_aspect` × height: people draw small boxes relatively
    /// wider (JAAD train's benchmark windows: a mean aspect of 0.46 for boxes under 60 px tall, 0.40 for boxes
    /// of 260 px and taller; `pedsynth calibrate` fits 5.8 px). 0 (the default): the narrowest box is
    /// `min_aspect` × height at every size.
    #[serde(skip_serializing_if = "super::is_zero")]
    pub width_pad_px: f64,
    /// Standard deviation of the per-frame noise on each edge, pixels.
    pub noise_px: f64,
    /// Edges on whole pixels, as annotation tools write them.
    pub whole_pixels: bool,
    /// Frames between the keyframes a person draws, `[min, max]` (each gap drawn per pedestrian and keyframe):
    /// between keyframes the tool interpolates the box's corner, width and height linearly and writes each on
    /// whole pixels, so the size holds for frames at a time as in JAAD. `[1, 1]` (the default) draws every
    /// frame.
    #[serde(skip_serializing_if = "is_every_frame")]
    pub keyframe_every: super::CountRange,
}

/// Whether keyframes are every frame (the default, left out of the resolved spec).
fn is_every_frame(r: &super::CountRange) -> bool {
    *r == super::CountRange(1, 1)
}

impl Default for AnnotatorBox {
    fn default() -> Self {
        AnnotatorBox {
            margin_frac: Range(0.0, 0.06),
            min_aspect: Range(0.3, 0.45),
            width_pad_px: 0.0,
            noise_px: 0.5,
            whole_pixels: true,
            keyframe_every: super::CountRange(1, 1),
        }
    }
}

/// The paper's four-stage visibility gate plus an occlusion threshold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Visibility {
    /// Stage 1: distance to the ego below this, metres.
    pub max_distance_m: f64,
    /// Stage 2: in front of the camera. Always true: a pedestrian behind the camera has no image box (the key
    /// is kept because the paper names the stage).
    pub require_in_front: bool,
    /// Stage 3: smallest box, pixels: `{width_px, height_px}` (or `[width, height]`).
    pub min_box_px: BoxSize,
    /// Beyond this distance the far minimum applies, metres.
    pub far_distance_m: f64,
    /// Stage 3 beyond `far_distance_m`: smallest box, pixels: `{width_px, height_px}` (or `[width, height]`).
    pub min_box_far_px: BoxSize,
    /// Stage 4: the box lies within the image.
    pub require_inside_image: bool,
    /// Pedestrians occluded by more than this fraction are not annotated.
    pub max_occlusion: f64,
}

impl Default for Visibility {
    fn default() -> Self {
        Visibility {
            max_distance_m: 70.0,
            require_in_front: true,
            min_box_px: BoxSize::new(15.0, 30.0),
            far_distance_m: 50.0,
            min_box_far_px: BoxSize::new(8.0, 15.0),
            require_inside_image: true,
            max_occlusion: 0.8,
        }
    }
}

/// The size of an image box, pixels. Written `{width_px: 15, height_px: 30}` or, briefly, `[15, 30]` (width
/// first); it is not a range, so the width may exceed the height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(from = "BoxSizeForm")]
pub struct BoxSize {
    /// Width, pixels.
    pub width_px: f64,
    /// Height, pixels.
    pub height_px: f64,
}

impl BoxSize {
    /// A box size.
    pub const fn new(width_px: f64, height_px: f64) -> BoxSize {
        BoxSize { width_px, height_px }
    }
}

/// The two ways to write a [`BoxSize`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, JsonSchema)]
#[serde(untagged, deny_unknown_fields)]
enum BoxSizeForm {
    /// `{width_px, height_px}`.
    Map {
        /// Width, pixels.
        width_px: f64,
        /// Height, pixels.
        height_px: f64,
    },
    /// `[width, height]`.
    List(f64, f64),
}

impl From<BoxSizeForm> for BoxSize {
    fn from(form: BoxSizeForm) -> BoxSize {
        match form {
            BoxSizeForm::Map { width_px, height_px } | BoxSizeForm::List(width_px, height_px) => {
                BoxSize { width_px, height_px }
            }
        }
    }
}

/// Keypoint formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PoseFormat {
    /// COCO-17 keypoints with COCO visibility flags.
    Coco17,
    /// OpenPose-18 (COCO-18) keypoints in the order PedestrianActionBenchmark reads (nose, neck, right
    /// shoulder/elbow/wrist, left shoulder/elbow/wrist, right hip/knee/ankle, left hip/knee/ankle, left eye,
    /// right eye, left ear, right ear); the neck is the shoulders' midpoint.
    Openpose18,
}

/// Output encodings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Parquet compression codec of the annotation tables.
    pub compression: Compression,
    /// zstd level (1–22).
    pub zstd_level: u32,
    /// Encoding of RGB frames.
    pub rgb_encoding: RgbEncoding,
    /// JPEG quality (1–100) when `rgb_encoding` is `jpeg`.
    pub jpeg_quality: u8,
    /// H.264 quantiser (0–51, lower is better; constant for every frame) when `rgb_encoding` is `h264`.
    pub h264_qp: u8,
    /// Encoding of depth images.
    pub depth_encoding: DepthEncoding,
    /// Encoding of DVS events.
    pub dvs_encoding: DvsEncoding,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            compression: Compression::Zstd,
            zstd_level: 3,
            rgb_encoding: RgbEncoding::Png,
            jpeg_quality: 90,
            h264_qp: 20,
            depth_encoding: DepthEncoding::MillimetresU16,
            dvs_encoding: DvsEncoding::Parquet,
        }
    }
}

/// Table compression codecs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// zstd.
    Zstd,
    /// Snappy.
    Snappy,
    /// No compression.
    None,
}

/// RGB frame encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RgbEncoding {
    /// One PNG per frame (fast compression).
    Png,
    /// One JPEG per frame (`jpeg_quality`, 4:2:0 chroma subsampling).
    Jpeg,
    /// One H.264 video per clip in MP4 (`sensors/rgb/<clip_id>.mp4`, sample i = frame i; constant quantiser
    /// `h264_qp`, 4:2:0 BT.601, an IDR frame every second). Needs an even width and height.
    H264,
}

/// Depth image encodings (both lossless).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DepthEncoding {
    /// 16-bit grayscale PNG of millimetres along the optical axis (65535: 65.535 m or farther, and the sky).
    #[serde(rename = "mm_u16")]
    MillimetresU16,
    /// CARLA's 24-bit encoding in an RGB PNG: `depth_m = 1000 (R + 256 G + 65536 B) / (2^24 − 1)`.
    #[serde(rename = "carla_rgb24")]
    CarlaRgb24,
}

/// DVS event encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DvsEncoding {
    /// A Parquet table per clip (frame, x, y, t_ns, polarity).
    Parquet,
}

/// Sanity limits; a spec beyond one is rejected unless `--allow-large` is given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Most clips in a dataset.
    pub max_clips: u64,
    /// Most pixels in one image (width × height).
    pub max_image_pixels: u64,
    /// Largest estimated dataset size, bytes.
    pub max_dataset_bytes: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_clips: 100_000,
            max_image_pixels: 3840 * 2160,
            max_dataset_bytes: 2_000_000_000_000,
        }
    }
}
