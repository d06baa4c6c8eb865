//! Scripted input for the previewer's photo mode (`mirage preview
//! PHOTO.json --script S.txt`): clicks, drags, typing and button presses
//! played into the window as the pointer and keyboard events egui gets from
//! a user, so that a test (or a demo) drives the very code a user does.
//!
//! One step a line; `#` starts a comment:
//!
//! - `click U V`: a click on the photo's pixel (U, V);
//! - `drag U0 V0 U1 V1`: press on pixel (U0, V0), move to (U1, V1) in four
//!   moves, release;
//! - `button LABEL`: a click on the middle of the widget labelled LABEL (a
//!   button, or `field NAME` for a text field), as drawn on the last frame;
//!   it waits up to 120 frames for the widget to appear;
//! - `type TEXT`: TEXT typed into the focused field;
//! - `wait N`: N frames with no input;
//! - `wait-fit`: until the running fit is done.
//!
//! A player sends at most one pointer event a frame (a press and its release
//! land in different frames, as a hand makes them), so egui sees each click
//! and drag as it would from a mouse.

use crate::error::{Error, Result};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// One step of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// A click on a photo pixel.
    Click([f64; 2]),
    /// A drag between photo pixels.
    Drag([f64; 2], [f64; 2]),
    /// A click on a labelled widget.
    Button(String),
    /// Text typed.
    Type(String),
    /// Frames with no input.
    Wait(u32),
    /// Until the fit is done.
    WaitFit,
}

/// One input event, in screen points.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// The pointer moved here.
    Move([f64; 2]),
    /// The primary button went down here.
    Press([f64; 2]),
    /// The primary button came up here.
    Release([f64; 2]),
    /// Text typed.
    Text(String),
}

/// What the player asks the window.
pub trait Stage {
    /// The screen point of photo pixel `p`.
    fn photo_to_screen(&self, p: [f64; 2]) -> Option<[f64; 2]>;
    /// The middle of the widget labelled `label` on the last frame.
    fn widget(&self, label: &str) -> Option<[f64; 2]>;
    /// Whether a fit is running.
    fn fitting(&self) -> bool;
}

/// Reads a script.
pub fn parse(text: &str, path: &Path) -> Result<Vec<(usize, Step)>> {
    let mut steps = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |m: String| Error::input(path, format!("line {}", i + 1), m);
        let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        let numbers = |n: usize| -> Result<Vec<f64>> {
            let v: Vec<f64> = rest
                .split_whitespace()
                .map(str::parse::<f64>)
                .collect::<std::result::Result<_, _>>()
                .map_err(|e| bad(format!("`{word}` takes {n} numbers: {e}")))?;
            if v.len() != n || v.iter().any(|x| !x.is_finite()) {
                return Err(bad(format!(
                    "`{word}` takes {n} finite numbers, got `{rest}`"
                )));
            }
            Ok(v)
        };
        let step = match word {
            "click" => {
                let v = numbers(2)?;
                Step::Click([v[0], v[1]])
            }
            "drag" => {
                let v = numbers(4)?;
                Step::Drag([v[0], v[1]], [v[2], v[3]])
            }
            "button" if !rest.is_empty() => Step::Button(rest.to_string()),
            "type" => Step::Type(rest.to_string()),
            "wait" => {
                let n = rest
                    .parse::<u32>()
                    .map_err(|e| bad(format!("`wait` takes a frame count: {e}")))?;
                Step::Wait(n)
            }
            "wait-fit" if rest.is_empty() => Step::WaitFit,
            _ => {
                return Err(bad(format!(
                    "`{line}`: expected click U V, drag U0 V0 U1 V1, button LABEL, type TEXT, wait N or wait-fit"
                )));
            }
        };
        steps.push((i + 1, step));
    }
    Ok(steps)
}

/// Frames a `button` step waits for its widget.
const WIDGET_PATIENCE: u32 = 120;

/// Frames with no input after a step's last event, so that the next step
/// finds the layout that step made (a button that appeared after a click
/// moves the ones below it: a `button` step read before the layout settled
/// pressed whatever had taken the old place).
const SETTLE_FRAMES: u32 = 3;

/// Plays a script, a frame at a time.
#[derive(Clone, Debug)]
pub struct Player {
    path: PathBuf,
    steps: VecDeque<(usize, Step)>,
    queue: VecDeque<Event>,
    wait: u32,
    tries: u32,
}

impl Player {
    /// A player of `steps` read from `path`.
    pub fn new(steps: Vec<(usize, Step)>, path: &Path) -> Player {
        Player {
            path: path.to_path_buf(),
            steps: steps.into(),
            queue: VecDeque::new(),
            wait: 0,
            tries: 0,
        }
    }

    /// Whether every step is played.
    pub fn done(&self) -> bool {
        self.steps.is_empty() && self.queue.is_empty() && self.wait == 0
    }

    /// This frame's events (at most one pointer event), or the error of a
    /// step that cannot be played.
    pub fn frame(&mut self, stage: &dyn Stage) -> Result<Vec<Event>> {
        if self.wait > 0 {
            self.wait -= 1;
            return Ok(Vec::new());
        }
        if let Some(e) = self.next_event() {
            return Ok(vec![e]);
        }
        let Some((line, step)) = self.steps.pop_front() else {
            return Ok(Vec::new());
        };
        let bad = |m: String| Error::input(&self.path, format!("line {line}"), m);
        let screen = |p: [f64; 2]| {
            stage
                .photo_to_screen(p)
                .ok_or_else(|| bad("the photo is not on screen".into()))
        };
        match step {
            Step::Click(p) => {
                let s = screen(p)?;
                self.queue
                    .extend([Event::Move(s), Event::Press(s), Event::Release(s)]);
            }
            Step::Drag(a, b) => {
                let (a, b) = (screen(a)?, screen(b)?);
                self.queue.extend([Event::Move(a), Event::Press(a)]);
                for k in 1..=4 {
                    let t = k as f64 / 4.0;
                    self.queue.push_back(Event::Move([
                        a[0] + t * (b[0] - a[0]),
                        a[1] + t * (b[1] - a[1]),
                    ]));
                }
                self.queue.push_back(Event::Release(b));
            }
            Step::Button(label) => match stage.widget(&label) {
                Some(c) => {
                    self.tries = 0;
                    self.queue
                        .extend([Event::Move(c), Event::Press(c), Event::Release(c)]);
                }
                None if self.tries < WIDGET_PATIENCE => {
                    self.tries += 1;
                    self.steps.push_front((line, Step::Button(label)));
                    return Ok(Vec::new());
                }
                None => {
                    return Err(bad(format!(
                        "no widget labelled `{label}` appeared in {WIDGET_PATIENCE} frames"
                    )));
                }
            },
            Step::Type(t) => self.queue.push_back(Event::Text(t)),
            Step::Wait(n) => self.wait = n,
            Step::WaitFit => {
                if stage.fitting() {
                    self.steps.push_front((line, Step::WaitFit));
                }
                return Ok(Vec::new());
            }
        }
        Ok(self.next_event().into_iter().collect())
    }

    /// The next queued event; after the last one, the frames to settle.
    fn next_event(&mut self) -> Option<Event> {
        let e = self.queue.pop_front()?;
        if self.queue.is_empty() {
            self.wait = SETTLE_FRAMES;
        }
        Some(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Fake {
        fitting: std::cell::Cell<u32>,
    }

    impl Stage for Fake {
        fn photo_to_screen(&self, p: [f64; 2]) -> Option<[f64; 2]> {
            Some([10.0 + 2.0 * p[0], 20.0 + 2.0 * p[1]])
        }
        fn widget(&self, label: &str) -> Option<[f64; 2]> {
            (label == "Fit").then_some([500.0, 40.0])
        }
        fn fitting(&self) -> bool {
            let n = self.fitting.get();
            self.fitting.set(n.saturating_sub(1));
            n > 0
        }
    }

    fn play(text: &str, fake: &Fake) -> Vec<Vec<Event>> {
        let steps = parse(text, Path::new("s.txt")).unwrap();
        let mut p = Player::new(steps, Path::new("s.txt"));
        let mut frames = Vec::new();
        while !p.done() {
            frames.push(p.frame(fake).unwrap());
            assert!(frames.len() < 1000);
        }
        frames
    }

    #[test]
    fn steps_become_one_pointer_event_a_frame_in_screen_points() {
        let fake = Fake { fitting: 3.into() };
        let frames = play(
            "click 5 5 # a comment\n\nbutton Fit\nwait-fit\ndrag 0 0 4 8\ntype 12.5\nwait 2\n",
            &fake,
        );
        let events: Vec<Event> = frames.iter().flatten().cloned().collect();
        assert!(frames.iter().all(|f| f.len() <= 1));
        let s = [20.0, 30.0];
        assert_eq!(
            events[..6],
            [
                Event::Move(s),
                Event::Press(s),
                Event::Release(s),
                Event::Move([500.0, 40.0]),
                Event::Press([500.0, 40.0]),
                Event::Release([500.0, 40.0]),
            ]
        );
        // The drag from photo (0, 0) to (4, 8): screen (10, 20) to (18, 36)
        // in four moves.
        assert_eq!(events[6], Event::Move([10.0, 20.0]), "{events:?}");
        assert_eq!(events[7], Event::Press([10.0, 20.0]));
        assert_eq!(events[8], Event::Move([12.0, 24.0]));
        assert_eq!(events[11], Event::Move([18.0, 36.0]));
        assert_eq!(events[12], Event::Release([18.0, 36.0]));
        assert_eq!(events[13], Event::Text("12.5".into()));
        assert_eq!(events.len(), 14);
        // The fit's three busy frames were waited out.
        assert_eq!(fake.fitting.get(), 0);
    }

    #[test]
    fn a_missing_widget_or_a_bad_line_is_an_error_naming_the_line() {
        let fake = Fake { fitting: 0.into() };
        let steps = parse("wait 1\nbutton Save", Path::new("s.txt")).unwrap();
        let mut p = Player::new(steps, Path::new("s.txt"));
        let err = loop {
            match p.frame(&fake) {
                Ok(_) => continue,
                Err(e) => break e,
            }
        };
        assert!(err.to_string().contains("line 2"), "{err}");
        assert!(err.to_string().contains("`Save`"), "{err}");
        for bad in ["click 1", "drag 1 2 3 x", "wait -1", "jump", "click 1 nan"] {
            let e = parse(&format!("wait 1\n{bad}"), Path::new("s.txt")).unwrap_err();
            assert!(e.to_string().contains("line 2"), "{bad}: {e}");
        }
    }
}
