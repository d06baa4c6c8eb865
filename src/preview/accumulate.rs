//! Progressive accumulation of samples while the window's view is still.
//!
//! At one sample per pixel the checkered ground of a problem's view aliases
//! into stripes at grazing angles, exactly where a mirage is. While anything
//! changes, every frame traces the window's "samples per frame" afresh; once
//! the view is still, each further frame traces the *next* samples of the
//! renderer's fixed sequence (`sample_offset(i)`, the same in the shader and
//! in [`crate::render::camera::sample_offset`]) and adds them to the sums
//! kept in the tracer's accumulation buffer, until the target count.
//!
//! Invariant (what the test checks): after the frames of a still view, the
//! image is the headless frame at `target` samples per pixel to rounding.
//! The shader sums a pixel's samples in f32 in the order of the sequence,
//! whether they come in one frame (headless: the running sum lives in the
//! ray's state) or over many (the window: it lives in the accumulation
//! buffer between frames), and divides by the same count; so both paths do
//! the same f32 additions in the same order, and agree bit for bit on a
//! device that runs the same shader the same way.
//!
//! This module is the bookkeeping only (which samples the next frame traces);
//! [`super::pack::SceneBuffers::set_samples`] puts them in the uniform block.

/// The most samples per pixel the window accumulates unless `--spp` says
/// otherwise.
pub const DEFAULT_TARGET: u32 = 16;

/// The samples of one frame: the sequence's `first` to `first + count − 1`,
/// added to the sums of the frames before when `first > 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Samples {
    /// Samples already in the accumulation buffer (the first index traced).
    pub first: u32,
    /// Samples this frame traces (≥ 1).
    pub count: u32,
}

impl Samples {
    /// The samples in the picture once this frame is traced.
    pub fn total(&self) -> u32 {
        self.first + self.count
    }
}

/// How many samples the picture holds, and how many it should.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Accumulation {
    target: u32,
    done: u32,
}

impl Accumulation {
    /// Accumulation up to `target` samples per pixel (at least 1).
    pub fn new(target: u32) -> Accumulation {
        Accumulation {
            target: target.max(1),
            done: 0,
        }
    }

    /// The samples the next frame traces, given whether the view is the one
    /// traced last (`still`) and the samples a frame takes (`per_frame`,
    /// at least 1): a view that changed starts afresh with `per_frame`
    /// samples (more than the target if asked: a moving view is never
    /// worse than the slider says); a still one adds up to `per_frame` more
    /// until the target; `None` once it holds them all (nothing to trace).
    pub fn next(&mut self, still: bool, per_frame: u32) -> Option<Samples> {
        let per_frame = per_frame.max(1);
        let samples = if !still || self.done == 0 {
            Samples {
                first: 0,
                count: per_frame,
            }
        } else if self.done < self.target {
            Samples {
                first: self.done,
                count: per_frame.min(self.target - self.done),
            }
        } else {
            return None;
        };
        self.done = samples.total();
        Some(samples)
    }

    /// Samples per pixel in the picture traced last.
    pub fn samples(&self) -> u32 {
        self.done
    }

    /// The most it accumulates.
    pub fn target(&self) -> u32 {
        self.target
    }

    /// Sets the target; a picture that already holds more is kept until the
    /// view changes.
    pub fn set_target(&mut self, target: u32) {
        self.target = target.max(1);
    }

    /// Whether the picture holds all the samples it should.
    pub fn complete(&self) -> bool {
        self.done >= self.target
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(acc: &mut Accumulation, per_frame: u32) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        let mut still = false;
        while let Some(s) = acc.next(still, per_frame) {
            out.push((s.first, s.count));
            still = true;
            assert!(out.len() < 100);
        }
        out
    }

    #[test]
    fn a_still_view_takes_the_next_samples_up_to_the_target() {
        let mut acc = Accumulation::new(8);
        assert_eq!(frames(&mut acc, 3), [(0, 3), (3, 3), (6, 2)]);
        assert_eq!(acc.samples(), 8);
        assert!(acc.complete());
        assert_eq!(acc.next(true, 3), None, "nothing left to trace");
        let mut one = Accumulation::new(4);
        assert_eq!(frames(&mut one, 1), [(0, 1), (1, 1), (2, 1), (3, 1)]);
    }

    #[test]
    fn a_change_starts_afresh_and_a_moving_view_keeps_its_samples_per_frame() {
        let mut acc = Accumulation::new(16);
        acc.next(false, 2);
        acc.next(true, 2);
        assert_eq!(acc.samples(), 4);
        assert_eq!(acc.next(false, 2), Some(Samples { first: 0, count: 2 }));
        let mut low = Accumulation::new(2);
        assert_eq!(low.next(false, 5), Some(Samples { first: 0, count: 5 }));
        assert_eq!(low.next(true, 5), None);
        low.set_target(9);
        assert_eq!(low.next(true, 5), Some(Samples { first: 5, count: 4 }));
    }
}
