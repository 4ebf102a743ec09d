//! Frame ranges for `render` and `reference` (issue 22): `--frames 1001-1100[:STEP]` renders
//! one image per frame, the scene read at the frame's USD time code (a glTF scene has no time:
//! every frame is the same), each written to the output path with the frame number put in
//! for `$F4` (zero-padded to four digits; `$F2`… likewise), `$F` (not padded) or a run of `#`
//! (padded to the run's length), the conventions of Houdini and Nuke.

use std::path::{Path, PathBuf};

/// First and last frame (both rendered when the step reaches them) and the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frames {
    pub first: i64,
    pub last: i64,
    pub step: i64,
}

impl Frames {
    /// The frames, in order.
    pub fn iter(self) -> impl Iterator<Item = i64> {
        (self.first..=self.last).step_by(self.step as usize)
    }
}

/// `FIRST-LAST[:STEP]` or `FRAME` (negative frames as in `-10--1`).
pub fn parse_frames(s: &str) -> Result<Frames, String> {
    let bad = || format!("expected FIRST-LAST[:STEP] or FRAME (e.g. 1001-1100:2), got \"{s}\"");
    let (range, step) = match s.split_once(':') {
        Some((r, st)) => (r, st.trim().parse::<i64>().map_err(|_| bad())?),
        None => (s, 1),
    };
    let range = range.trim();
    // The separating '-' is the first one after the first character (which may be a sign).
    let split = range
        .char_indices()
        .skip(1)
        .find(|&(_, c)| c == '-')
        .map(|(i, _)| i);
    let (first, last) = match split {
        Some(i) => (
            range[..i].trim().parse::<i64>().map_err(|_| bad())?,
            range[i + 1..].trim().parse::<i64>().map_err(|_| bad())?,
        ),
        None => {
            let f = range.parse::<i64>().map_err(|_| bad())?;
            (f, f)
        }
    };
    if step < 1 {
        return Err(format!("the frame step must be at least 1, got {step}"));
    }
    if last < first {
        return Err(format!(
            "the last frame {last} comes before the first {first}"
        ));
    }
    Ok(Frames { first, last, step })
}

/// `pattern` with `frame` put in for its `$F<digits>`, `$F` or `#` run; `None` where it has no
/// such token (every frame would overwrite one file).
pub fn frame_path(pattern: &Path, frame: i64) -> Option<PathBuf> {
    let text = pattern.to_str()?;
    let mut out = String::with_capacity(text.len() + 8);
    let mut found = false;
    let mut rest = text;
    while let Some(c) = rest.chars().next() {
        if let Some(after) = rest.strip_prefix("$F") {
            let digits = after.chars().take_while(char::is_ascii_digit).count();
            let width: usize = after[..digits].parse().unwrap_or(0);
            out.push_str(&padded(frame, width));
            rest = &after[digits..];
            found = true;
        } else if c == '#' {
            let run = rest.chars().take_while(|&c| c == '#').count();
            out.push_str(&padded(frame, run));
            rest = &rest[run..];
            found = true;
        } else {
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    found.then(|| PathBuf::from(out))
}

/// [`frame_path`], or the error that names the path without a frame token.
pub fn named(pattern: &Path, frame: i64) -> anyhow::Result<PathBuf> {
    frame_path(pattern, frame).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: with --frames the name needs $F4, $F or #### where the frame number goes",
            pattern.display()
        )
    })
}

/// `frame` zero-padded to `width` digits (the sign before the zeros).
fn padded(frame: i64, width: usize) -> String {
    if frame < 0 {
        format!("-{:0width$}", frame.unsigned_abs())
    } else {
        format!("{frame:0width$}")
    }
}

/// One frame a command writes.
pub struct FrameOutput {
    /// The frame's time code (`None`: the run's `--time-code`).
    pub time: Option<f64>,
    pub output: PathBuf,
    pub png: Option<PathBuf>,
}

/// The frames a command writes: one, at the run's time code, without `frames`; with them,
/// each frame, its paths named by [`frame_path`]. A pattern without a token, or frames with
/// `--time-code`, is refused.
pub fn outputs(
    frames: Option<Frames>,
    output: &Path,
    png: Option<&Path>,
) -> anyhow::Result<Vec<FrameOutput>> {
    let Some(frames) = frames else {
        return Ok(vec![FrameOutput {
            time: None,
            output: output.to_path_buf(),
            png: png.map(Path::to_path_buf),
        }]);
    };
    if crate::time_code_given() {
        anyhow::bail!("--frames reads the scene at each frame's time code: leave out --time-code");
    }
    frames
        .iter()
        .map(|f| {
            Ok(FrameOutput {
                time: Some(f as f64),
                output: named(output, f)?,
                png: png.map(|p| named(p, f)).transpose()?,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_step() {
        let f = parse_frames("1001-1005:2").expect("range");
        assert_eq!(f.iter().collect::<Vec<_>>(), [1001, 1003, 1005]);
        assert_eq!(parse_frames("7").expect("one").iter().count(), 1);
        assert_eq!(
            parse_frames("-2-1")
                .expect("signed")
                .iter()
                .collect::<Vec<_>>(),
            [-2, -1, 0, 1]
        );
        for bad in ["", "a-b", "5-1", "1-5:0", "1-5:x", "1--"] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn tokens_take_the_frame() {
        let p = |s: &str, f| frame_path(Path::new(s), f).map(|p| p.display().to_string());
        assert_eq!(p("out.$F4.exr", 7).as_deref(), Some("out.0007.exr"));
        assert_eq!(p("out.$F.exr", 1001).as_deref(), Some("out.1001.exr"));
        assert_eq!(
            p("shot/beauty.####.exr", 42).as_deref(),
            Some("shot/beauty.0042.exr")
        );
        assert_eq!(p("f#.exr", 1001).as_deref(), Some("f1001.exr"));
        assert_eq!(p("f.$F3.exr", -4).as_deref(), Some("f.-004.exr"));
        assert_eq!(p("still.exr", 1), None);
    }
}
