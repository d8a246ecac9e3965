//! Playing a character's animation: which sampled pose of the mesh's rig the view shows at a
//! time of an animation, and how each part's volume moves with its bone there.
//!
//! The view shows the sampled pose nearest to the time: the mesh as the loader skinned it in
//! that pose ([`bvseg_core::Pose::vertices`]; the loader samples every key of an animation and
//! the midpoints between keys), and each volume moved by `G_b(t) · G_b(rest)⁻¹`, the motion
//! under which the core fitted it to enclose its part's triangles. Nothing is interpolated
//! between samples: the rig holds posed vertices, not the skin's bind matrices that skinning
//! at another time would need, and the core guarantees the enclosure exactly at the samples.
use bvseg_core::{Pose, Rig, Skeleton};
use glam::DMat4;

/// Longest time a frame advances a playing animation, in seconds: after a stall (a slow
/// frame, a hidden window) the animation goes on from where it was rather than jumping.
pub const MAX_FRAME_STEP: f64 = 0.25;

/// One animation of the rig: its sampled poses in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct Clip {
    /// The animation's name (as the file names it, or `animation N`).
    pub name: String,
    /// Indices into the skin's poses, in time order.
    poses: Vec<usize>,
    /// Their times, in seconds, ascending.
    times: Vec<f64>,
}

impl Clip {
    /// Time of the first sampled pose, in seconds.
    pub fn start(&self) -> f64 {
        self.times.first().copied().unwrap_or(0.0)
    }

    /// Time of the last sampled pose, in seconds.
    pub fn end(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Number of sampled poses.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether the clip has no pose (never, for a clip of a [`Player`]).
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The position in this clip of the sampled pose nearest to `time` (the earlier of two
    /// as near).
    fn nearest(&self, time: f64) -> usize {
        let i = self.times.partition_point(|&t| t < time);
        match (i.checked_sub(1), self.times.get(i)) {
            (Some(before), Some(&after)) if time - self.times[before] <= after - time => before,
            (Some(before), None) => before,
            _ => i.min(self.times.len().saturating_sub(1)),
        }
    }
}

/// The state of the animation controls: which animation, at what time, playing or not, or
/// the rest pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Player {
    clips: Vec<Clip>,
    clip: usize,
    time: f64,
    playing: bool,
    at_rest: bool,
}

impl Player {
    /// The controls for a mesh whose rig has sampled poses (`None` for any other mesh), at
    /// the rest pose and paused. `names` are the animations' names as the loader read them
    /// (indexed by [`Pose::animation`]); one it lacks is called `animation N`.
    pub fn new(rig: Option<&Rig>, names: &[String]) -> Option<Self> {
        let poses = &rig?.skin.as_ref()?.poses;
        let count = poses.iter().map(|p| p.animation + 1).max()?;
        let clips: Vec<Clip> = (0..count)
            .filter_map(|a| {
                let mut of: Vec<usize> = (0..poses.len())
                    .filter(|&i| poses[i].animation == a && poses[i].time.is_finite())
                    .collect();
                of.sort_by(|&i, &j| poses[i].time.total_cmp(&poses[j].time));
                (!of.is_empty()).then(|| Clip {
                    name: names
                        .get(a)
                        .cloned()
                        .unwrap_or_else(|| format!("animation {a}")),
                    times: of.iter().map(|&i| poses[i].time).collect(),
                    poses: of,
                })
            })
            .collect();
        let time = clips.first()?.start();
        Some(Self {
            clips,
            clip: 0,
            time,
            playing: false,
            at_rest: true,
        })
    }

    /// The rig's animations that have poses.
    pub fn clips(&self) -> &[Clip] {
        &self.clips
    }

    /// The animation chosen (an index into [`Self::clips`]).
    pub fn clip(&self) -> usize {
        self.clip
    }

    /// Chooses animation `i` (if there is one), from its start.
    pub fn set_clip(&mut self, i: usize) {
        if i < self.clips.len() && i != self.clip {
            self.clip = i;
            self.time = self.clips[i].start();
        }
    }

    /// The time in the chosen animation, in seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Shows the pose at `time` (clamped to the animation's span), leaving the rest pose.
    pub fn set_time(&mut self, time: f64) {
        let c = &self.clips[self.clip];
        if time.is_finite() {
            self.time = time.clamp(c.start(), c.end());
        }
        self.at_rest = false;
    }

    /// Whether the animation is playing.
    pub fn playing(&self) -> bool {
        self.playing
    }

    /// Plays from the time shown (leaving the rest pose).
    pub fn play(&mut self) {
        self.playing = true;
        self.at_rest = false;
    }

    /// Stops at the pose shown.
    pub fn pause(&mut self) {
        self.playing = false;
    }

    /// Whether the rest pose (the mesh as loaded) is shown.
    pub fn at_rest(&self) -> bool {
        self.at_rest
    }

    /// Stops and shows the rest pose.
    pub fn rest(&mut self) {
        self.playing = false;
        self.at_rest = true;
    }

    /// Moves a playing animation on by `dt` seconds (at most [`MAX_FRAME_STEP`]), from its
    /// end back to its start.
    pub fn advance(&mut self, dt: f64) {
        // NaN is not a step either.
        if !self.playing || dt.is_nan() || dt <= 0.0 {
            return;
        }
        let c = &self.clips[self.clip];
        let span = c.end() - c.start();
        if span > 0.0 {
            let t = self.time - c.start() + dt.min(MAX_FRAME_STEP);
            self.time = c.start() + t.rem_euclid(span);
        }
    }

    /// The sampled pose shown (an index into the skin's poses), `None` at rest.
    pub fn pose(&self) -> Option<usize> {
        if self.at_rest {
            return None;
        }
        let c = &self.clips[self.clip];
        c.poses.get(c.nearest(self.time)).copied()
    }

    /// The position of the pose shown among its animation's poses (from 0), `None` at rest.
    pub fn pose_in_clip(&self) -> Option<usize> {
        (!self.at_rest).then(|| self.clips[self.clip].nearest(self.time))
    }
}

/// Each volume's motion from the rest pose to `pose`: `G_b(pose) · G_b(rest)⁻¹` for a volume
/// bound to bone `b` of `skeleton`, the identity for one without a bone (it does not move),
/// or with a bone the pose lacks.
pub fn motions(
    bones: impl IntoIterator<Item = Option<usize>>,
    skeleton: &Skeleton,
    pose: &Pose,
) -> Vec<DMat4> {
    bones
        .into_iter()
        .map(|b| {
            b.and_then(|b| Some(*pose.joints.get(b)? * skeleton.joints.get(b)?.rest.inverse()))
                .unwrap_or(DMat4::IDENTITY)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvseg_core::{Joint, Skin};
    use glam::DVec3;

    /// A rig of one joint with poses `(animation, time)`, listed in that order; the joint is
    /// moved up by the time in each.
    fn rig(poses: &[(usize, f64)]) -> Rig {
        Rig {
            skeleton: Skeleton {
                joints: vec![Joint {
                    name: "root".into(),
                    parent: None,
                    rest: DMat4::from_translation(DVec3::X),
                    node: None,
                }],
            },
            skin: Some(Skin {
                weights: Vec::new(),
                corners: Vec::new(),
                poses: poses
                    .iter()
                    .map(|&(animation, time)| Pose {
                        animation,
                        time,
                        joints: vec![DMat4::from_translation(DVec3::new(1.0, time, 0.0))],
                        vertices: Vec::new(),
                    })
                    .collect(),
            }),
        }
    }

    #[test]
    fn no_poses_no_player() {
        assert!(Player::new(None, &[]).is_none());
        assert!(Player::new(Some(&Rig::default()), &[]).is_none());
        assert!(Player::new(Some(&rig(&[])), &[]).is_none());
    }

    #[test]
    fn the_nearest_sampled_pose_of_the_chosen_animation_is_shown() {
        // Two animations, the second listed out of time order.
        let r = rig(&[(0, 0.0), (0, 0.5), (0, 1.0), (1, 2.0), (1, 1.0)]);
        let mut p = Player::new(Some(&r), &["walk".into()]).unwrap();
        let names: Vec<&str> = p.clips().iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["walk", "animation 1"]);
        assert!(p.at_rest() && !p.playing());
        assert_eq!(p.pose(), None);
        p.set_time(0.3);
        assert_eq!((p.pose(), p.pose_in_clip()), (Some(1), Some(1)));
        p.set_time(0.2);
        assert_eq!(p.pose(), Some(0));
        p.set_time(0.25);
        assert_eq!(p.pose(), Some(0), "a tie goes to the earlier pose");
        p.set_time(7.0);
        assert_eq!((p.time(), p.pose()), (1.0, Some(2)), "clamped to the end");
        p.set_clip(1);
        assert_eq!((p.time(), p.pose()), (1.0, Some(4)), "from its start");
        p.set_time(1.9);
        assert_eq!(p.pose(), Some(3));
        p.rest();
        assert_eq!(p.pose(), None);
    }

    #[test]
    fn playing_advances_by_the_frame_time_and_loops() {
        let r = rig(&[(0, 1.0), (0, 2.0), (0, 3.0)]);
        let mut p = Player::new(Some(&r), &[]).unwrap();
        assert_eq!(p.time(), 1.0);
        p.advance(0.125);
        assert_eq!(p.time(), 1.0, "paused: no change");
        p.play();
        assert!(!p.at_rest());
        p.advance(0.125);
        assert_eq!(p.time(), 1.125);
        for _ in 0..15 {
            p.advance(0.125);
        }
        // 1 + 16 / 8 = 3: the end is the start again.
        assert_eq!(p.time(), 1.0);
        p.advance(10.0);
        assert_eq!(
            p.time(),
            1.0 + MAX_FRAME_STEP,
            "a stall counts as one step at most"
        );
        p.advance(f64::NAN);
        p.advance(-1.0);
        assert_eq!(p.time(), 1.0 + MAX_FRAME_STEP);
        p.pause();
        assert!(!p.playing() && !p.at_rest());
    }

    #[test]
    fn volumes_move_by_their_bones_pose_over_its_rest() {
        let r = rig(&[(0, 0.5)]);
        let pose = &r.skin.as_ref().unwrap().poses[0];
        let m = motions([Some(0), None, Some(3)], &r.skeleton, pose);
        // The joint rests at x = 1 and is at (1, 0.5, 0) in the pose: a lift by 0.5.
        let p = m[0].transform_point3(DVec3::new(2.0, 0.0, 0.0));
        assert!((p - DVec3::new(2.0, 0.5, 0.0)).length() < 1e-12, "{p}");
        assert_eq!(&m[1..], [DMat4::IDENTITY; 2]);
    }
}
