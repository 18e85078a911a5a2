//! `--script FILE` (hidden, for tests and demos): synthetic input events per
//! frame, fed through the same [`super::controls`] as the window's events.
//!
//! One event per line, `FRAME EVENT [ARGS]`; `#` starts a comment. Events of a
//! frame are applied in file order before that frame (frame 0 is the first)
//! is drawn:
//!
//! ```text
//! 0  key Right      # press and release (Right, Left, Up, Down, z, F12, Esc, ...)
//! 2  press w        # hold ...
//! 9  release w      # ... and let go
//! 3  drag 20 -5     # left-button drag by (dx, dy) pixels, y down
//! 4  resize 300 200 # ask the window system for a new window size
//! ```

use super::controls::{Input, Key};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    #[error("cannot read the script {file}: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}:{line}: {what}")]
    Syntax {
        file: String,
        line: usize,
        what: String,
    },
}

/// One scripted event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// Input for the controls.
    Input(Input),
    /// A window size request (width, height in pixels).
    Resize(u32, u32),
}

/// A parsed script: `(frame, event)` pairs sorted by frame (file order within
/// a frame).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    events: Vec<(u64, Event)>,
    next: usize,
}

impl Script {
    pub fn load(path: &Path) -> Result<Script, ScriptError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScriptError::Io {
            file: path.display().to_string(),
            source,
        })?;
        Script::parse(&text, &path.display().to_string())
    }

    pub fn parse(text: &str, file: &str) -> Result<Script, ScriptError> {
        let mut events = Vec::new();
        for (index, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |what: String| ScriptError::Syntax {
                file: file.to_string(),
                line: index + 1,
                what,
            };
            let words: Vec<&str> = line.split_whitespace().collect();
            let frame: u64 = words[0]
                .parse()
                .map_err(|_| err(format!("frame {:?} is not a whole number", words[0])))?;
            let key = |i: usize| -> Result<Key, ScriptError> {
                let name = words.get(i).copied().unwrap_or("");
                Key::parse(name).ok_or_else(|| err(format!("unknown key {name:?}")))
            };
            let number = |i: usize| -> Result<f64, ScriptError> {
                let w = words.get(i).copied().unwrap_or("");
                w.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| err(format!("{w:?} is not a finite number of pixels")))
            };
            let pixels = |i: usize| -> Result<u32, ScriptError> {
                let w = words.get(i).copied().unwrap_or("");
                w.parse::<u32>()
                    .ok()
                    .filter(|v| (1..=solution::camera::MAX_IMAGE_SIDE).contains(v))
                    .ok_or_else(|| {
                        err(format!(
                            "{w:?} is not a window size in 1..={} pixels",
                            solution::camera::MAX_IMAGE_SIDE
                        ))
                    })
            };
            let mut push = |event: Event| events.push((frame, event));
            let want = |n: usize| -> Result<(), ScriptError> {
                if words.len() == n {
                    Ok(())
                } else {
                    Err(err(format!(
                        "`{}` takes {} argument(s), found {}",
                        words.get(1).copied().unwrap_or(""),
                        n - 2,
                        words.len().saturating_sub(2)
                    )))
                }
            };
            match words.get(1).copied() {
                Some("key") => {
                    want(3)?;
                    let k = key(2)?;
                    push(Event::Input(Input::KeyDown {
                        key: k,
                        repeat: false,
                    }));
                    push(Event::Input(Input::KeyUp(k)));
                }
                Some("press") => {
                    want(3)?;
                    push(Event::Input(Input::KeyDown {
                        key: key(2)?,
                        repeat: false,
                    }));
                }
                Some("release") => {
                    want(3)?;
                    push(Event::Input(Input::KeyUp(key(2)?)));
                }
                Some("drag") => {
                    want(4)?;
                    let (dx, dy) = (number(2)?, number(3)?);
                    push(Event::Input(Input::ButtonDown));
                    push(Event::Input(Input::PointerMoved { dx, dy }));
                    push(Event::Input(Input::ButtonUp));
                }
                Some("resize") => {
                    want(4)?;
                    push(Event::Resize(pixels(2)?, pixels(3)?));
                }
                other => {
                    return Err(err(format!(
                        "unknown event {:?} (key, press, release, drag or resize)",
                        other.unwrap_or("")
                    )))
                }
            }
        }
        // Stable: file order within a frame.
        events.sort_by_key(|(frame, _)| *frame);
        Ok(Script { events, next: 0 })
    }

    /// The events of `frame` (and of any earlier frame not yet taken).
    pub fn take(&mut self, frame: u64) -> Vec<Event> {
        let mut out = Vec::new();
        while let Some(&(f, input)) = self.events.get(self.next) {
            if f > frame {
                break;
            }
            out.push(input);
            self.next += 1;
        }
        out
    }

    /// The last frame with an event (None for an empty script).
    pub fn last_frame(&self) -> Option<u64> {
        self.events.last().map(|(f, _)| *f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_events_in_frame_order() {
        let text = "# test\n2 drag 5 -1.5\n0 key Right\n0 key z # zoom\n1 press w\n3 release w\n\
                    3 resize 320 200\n";
        let mut s = Script::parse(text, "s.txt").unwrap();
        assert_eq!(s.last_frame(), Some(3));
        let down = |key| Event::Input(Input::KeyDown { key, repeat: false });
        let up = |key| Event::Input(Input::KeyUp(key));
        assert_eq!(
            s.take(0),
            vec![
                down(Key::Right),
                up(Key::Right),
                down(Key::Char('z')),
                up(Key::Char('z'))
            ]
        );
        assert_eq!(s.take(1), vec![down(Key::Char('w'))]);
        assert_eq!(
            s.take(2),
            [
                Input::ButtonDown,
                Input::PointerMoved { dx: 5.0, dy: -1.5 },
                Input::ButtonUp
            ]
            .map(Event::Input)
        );
        assert_eq!(s.take(9), vec![up(Key::Char('w')), Event::Resize(320, 200)]);
        assert!(s.take(10).is_empty());
    }

    #[test]
    fn errors_name_file_line_and_value() {
        for (text, want) in [
            ("0 key Right\nx key z\n", "s:2: frame \"x\""),
            ("0 key Hyper\n", "s:1: unknown key \"Hyper\""),
            ("0 jump\n", "s:1: unknown event \"jump\""),
            ("0 drag 1\n", "s:1: `drag` takes 2 argument(s), found 1"),
            ("0 drag 1 nan\n", "s:1: \"nan\" is not a finite"),
            ("0 key\n", "s:1: `key` takes 1 argument(s), found 0"),
            ("0 resize 0 10\n", "s:1: \"0\" is not a window size"),
        ] {
            let msg = Script::parse(text, "s").unwrap_err().to_string();
            assert!(msg.starts_with(want), "{msg}");
        }
    }
}
