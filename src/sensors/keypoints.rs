//! Keypoint formats: COCO-17's joint names and order, and OpenPose-18's (PedestrianActionBenchmark's) order
//! built from COCO-17's, with its neck derived from the shoulders.

use crate::spec::types::PoseFormat;

/// COCO-17 keypoint names, in COCO order.
pub const COCO17: [&str; 17] = [
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

/// OpenPose-18 joints (PedestrianActionBenchmark's order) as COCO-17 indices; the neck (`None`) is the
/// shoulders' midpoint.
pub const OPENPOSE18_FROM_COCO17: [Option<usize>; 18] = [
    Some(0),  // nose
    None,     // neck
    Some(6),  // right shoulder
    Some(8),  // right elbow
    Some(10), // right wrist
    Some(5),  // left shoulder
    Some(7),  // left elbow
    Some(9),  // left wrist
    Some(12), // right hip
    Some(14), // right knee
    Some(16), // right ankle
    Some(11), // left hip
    Some(13), // left knee
    Some(15), // left ankle
    Some(1),  // left eye
    Some(2),  // right eye
    Some(3),  // left ear
    Some(4),  // right ear
];

/// The number of joints of a keypoint format.
pub fn joint_count(format: PoseFormat) -> usize {
    match format {
        PoseFormat::Coco17 => 17,
        PoseFormat::Openpose18 => 18,
    }
}

/// Appends the 17 COCO-order triplets of `coco` to `out` in `format`'s joint order. The third value of each
/// triplet is a visibility flag when `flags` (a derived joint takes the lower of its sources' flags) and a
/// coordinate otherwise (averaged like the first two).
pub fn push_keypoints(coco: &[f32; 51], format: PoseFormat, flags: bool, out: &mut Vec<f32>) {
    match format {
        PoseFormat::Coco17 => out.extend_from_slice(coco),
        PoseFormat::Openpose18 => {
            for joint in OPENPOSE18_FROM_COCO17 {
                match joint {
                    Some(k) => out.extend_from_slice(&coco[3 * k..3 * k + 3]),
                    None => {
                        let (l, r) = (&coco[15..18], &coco[18..21]);
                        let third = if flags { l[2].min(r[2]) } else { 0.5 * (l[2] + r[2]) };
                        out.extend_from_slice(&[0.5 * (l[0] + r[0]), 0.5 * (l[1] + r[1]), third]);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn openpose18_reorders_coco17_and_derives_the_neck() {
        let mut coco = [0f32; 51];
        for k in 0..17 {
            coco[3 * k..3 * k + 3].copy_from_slice(&[k as f32, 100.0 + k as f32, 2.0]);
        }
        coco[3 * 6 + 2] = 1.0; // the right shoulder is occluded
        let mut out = Vec::new();
        push_keypoints(&coco, PoseFormat::Openpose18, true, &mut out);
        assert_eq!(out.len(), 54);
        assert_eq!(&out[0..3], &[0.0, 100.0, 2.0], "nose first");
        assert_eq!(
            &out[3..6],
            &[5.5, 105.5, 1.0],
            "neck: shoulders' midpoint, the lower flag"
        );
        assert_eq!(&out[6..9], &[6.0, 106.0, 1.0], "right shoulder");
        assert_eq!(&out[15..18], &[5.0, 105.0, 2.0], "left shoulder");
        assert_eq!(&out[42..45], &[1.0, 101.0, 2.0], "left eye");
        assert_eq!(&out[51..54], &[4.0, 104.0, 2.0], "right ear last");
        out.clear();
        push_keypoints(&coco, PoseFormat::Coco17, true, &mut out);
        assert_eq!(out, coco);
    }
}
