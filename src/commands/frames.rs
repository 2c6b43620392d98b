//! `cltrace render --frames A..B`: frames of a scene's camera animation
//! ([`crate::animation`]), each rendered on its own, as a separate job would render it, to
//! outputs named by a frame pattern (`out_%04d.png`).

use std::path::{Path, PathBuf};
use std::str::FromStr;

use super::Ending;
use super::render::{RenderRequest, render_single};
use crate::error::{Error, Result};
use crate::input::scene_file::SceneDescription;

/// The frames `--frames` names, first to last, both included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    first: u32,
    last: u32,
}

impl FrameRange {
    fn count(self) -> u64 {
        (self.last - self.first) as u64 + 1
    }
}

impl FromStr for FrameRange {
    type Err = String;

    /// `A..B` (A to B - 1, as Rust's ranges), `A..=B` (A to B) or `N` (frame N alone).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let number = |t: &str| {
            t.trim().parse::<u32>().map_err(|_| {
                format!(
                    "`{s}` is not a frame range: give A..B (frames A to B-1), A..=B (A to B) \
                     or N (frame N), in whole numbers 0 or more"
                )
            })
        };
        let Some((a, b)) = s.split_once("..") else {
            let n = number(s)?;
            return Ok(FrameRange { first: n, last: n });
        };
        let first = number(a)?;
        let last = match b.strip_prefix('=') {
            Some(b) => Some(number(b)?).filter(|&l| l >= first),
            None => number(b)?.checked_sub(1).filter(|&l| l >= first),
        };
        last.map(|last| FrameRange { first, last }).ok_or_else(|| {
            format!(
                "`{s}` holds no frame: the end must come after the start (A..B is frames A to \
                 B-1, A..=B frames A to B)"
            )
        })
    }
}

/// `--frames` and how it treats frames already rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frames {
    /// The frames to render.
    pub range: FrameRange,
    /// Leave a frame whose outputs all exist as it is (`--skip-existing`, to resume a run).
    pub skip_existing: bool,
}

/// A piece of an output path: text, or the frame number printed `width` digits wide at
/// least, zero-padded.
#[derive(Clone, Debug, PartialEq)]
enum Piece {
    Text(String),
    Frame {
        width: usize,
    },
    /// A `%` that starts neither `%d`, `%0Nd` nor `%%`.
    Stray(String),
}

/// The longest `%0Nd` accepted: a `u32` has at most 10 digits.
const MAX_WIDTH: usize = 10;

/// `text` cut into pieces, printf's way: `%d`, `%0Nd` and `%%` (a percent sign).
fn pieces(text: &str) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut literal = String::new();
    let mut rest = text;
    while let Some(i) = rest.find('%') {
        literal.push_str(&rest[..i]);
        rest = &rest[i + 1..];
        if let Some(after) = rest.strip_prefix('%') {
            literal.push('%');
            rest = after;
            continue;
        }
        let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
        let (number, after) = rest.split_at(digits);
        let width = match number {
            "" => Some(0),
            n if n.starts_with('0') => n.parse::<usize>().ok().filter(|&w| w <= MAX_WIDTH),
            _ => None,
        };
        match (width, after.strip_prefix('d')) {
            (Some(width), Some(after)) => {
                out.push(Piece::Text(std::mem::take(&mut literal)));
                out.push(Piece::Frame { width });
                rest = after;
            }
            _ => {
                let end = after.chars().next().map_or(0, char::len_utf8);
                out.push(Piece::Text(std::mem::take(&mut literal)));
                out.push(Piece::Stray(format!("%{number}{}", &after[..end])));
                rest = &after[end..];
            }
        }
    }
    literal.push_str(rest);
    out.push(Piece::Text(literal));
    out.retain(|p| *p != Piece::Text(String::new()));
    out
}

/// An output path with one frame number in it (`out_%04d.png`).
#[derive(Clone, Debug, PartialEq)]
struct Pattern(Vec<Piece>);

impl Pattern {
    /// The pattern of the output `flag` names; an error unless `path` holds exactly one
    /// `%d` or `%0Nd` and no other `%` than `%%`.
    fn of(flag: &str, path: &Path) -> Result<Self> {
        let Some(text) = path.to_str() else {
            return Err(Error::Invalid(format!(
                "{flag} {}: a frame pattern must be UTF-8",
                path.display()
            )));
        };
        let pieces = pieces(text);
        if let Some(Piece::Stray(s)) = pieces.iter().find(|p| matches!(p, Piece::Stray(_))) {
            return Err(Error::Invalid(format!(
                "{flag} {text}: `{s}` is no frame number: use %d, or %0Nd for N digits \
                 (N up to {MAX_WIDTH}), and %% for a percent sign"
            )));
        }
        match pieces
            .iter()
            .filter(|p| matches!(p, Piece::Frame { .. }))
            .count()
        {
            1 => Ok(Pattern(pieces)),
            0 => Err(Error::Invalid(format!(
                "--frames needs a frame number in {flag}'s file name, such as out_%04d.png \
                 (%d, or %0Nd for N digits); {text} has none"
            ))),
            n => Err(Error::Invalid(format!(
                "{flag} {text} has {n} frame numbers: give one"
            ))),
        }
    }

    fn path(&self, frame: u32) -> PathBuf {
        let mut text = String::new();
        for piece in &self.0 {
            match piece {
                Piece::Text(t) | Piece::Stray(t) => text.push_str(t),
                Piece::Frame { width } => text.push_str(&format!("{frame:0width$}")),
            }
        }
        PathBuf::from(text)
    }
}

/// Refuses an output that holds a frame pattern when `--frames` is not given: it would be
/// written under its pattern's name, surely not what was meant.
pub(crate) fn refuse_patterns(req: &RenderRequest) -> Result<()> {
    let outputs = [Some(&req.output), req.hits.as_ref(), req.json.as_ref()];
    for (flag, path) in ["-o", "--hits", "--json"].into_iter().zip(outputs) {
        let Some(path) = path else { continue };
        let text = path.to_string_lossy();
        if pieces(&text)
            .iter()
            .any(|p| matches!(p, Piece::Frame { .. }))
        {
            return Err(Error::Invalid(format!(
                "{flag} {text} holds a frame number pattern: give --frames A..B to render \
                 frames, or a plain file name"
            )));
        }
    }
    Ok(())
}

/// Renders `frames` of the scene's animation, one after the other, each as
/// [`render_single`] renders one image, to the frame patterns of `-o` (and `--hits` and
/// `--json`, which need one too when given). A frame that fails ends the run with its
/// error; the frames written before it stay. Interrupted (Ctrl-C) after a frame was
/// written, the ending is [`Ending::Partial`].
pub(crate) fn render_frames(req: &RenderRequest, frames: &Frames) -> Result<Ending> {
    let v = req.verbosity;
    let image = Pattern::of("-o", &req.output)?;
    let hits = req.hits.as_deref().map(|p| Pattern::of("--hits", p));
    let json = req.json.as_deref().map(|p| Pattern::of("--json", p));
    let (hits, json) = (hits.transpose()?, json.transpose()?);
    let scene = SceneDescription::named(req.scene.as_deref())?;
    if scene.animation.is_none() {
        let what = match &req.scene {
            Some(path) => path.display().to_string(),
            None => "the built-in default scene".to_string(),
        };
        return Err(Error::Invalid(format!(
            "--frames: {what} has no camera animation; give a scene file with \
             [[camera.keyframe]] tables or a [camera.turntable]"
        )));
    }
    let range = frames.range;
    let (count, mut written, mut skipped) = (range.count(), 0u64, 0u64);
    for (i, frame) in (range.first..=range.last).enumerate() {
        let request = RenderRequest {
            output: image.path(frame),
            hits: hits.as_ref().map(|p| p.path(frame)),
            json: json.as_ref().map(|p| p.path(frame)),
            frames: None,
            frame,
            ..req.clone()
        };
        let which = format!("frame {frame} ({} of {count})", i + 1);
        let exists = std::iter::once(&request.output)
            .chain(&request.hits)
            .chain(&request.json)
            .all(|p| p.exists());
        if frames.skip_existing && exists {
            v.say(format!(
                "{which}: {} exists, skipped (--skip-existing)",
                request.output.display()
            ));
            skipped += 1;
            continue;
        }
        v.say(&which);
        let stopped = match render_single(&request) {
            Ok(Ending::Complete) => {
                written += 1;
                let more = frame < range.last;
                (more && crate::interrupt::requested()).then(|| format!("after frame {frame}"))
            }
            Ok(Ending::Partial) => {
                written += 1;
                Some(format!("frame {frame} has fewer samples"))
            }
            // What is written is a partial result, as a partial image would be.
            Err(Error::Interrupted) if written > 0 => Some(format!("frame {frame} not written")),
            Err(Error::Invalid(message)) => {
                return Err(Error::Invalid(format!("frame {frame}: {message}")));
            }
            Err(e) => return Err(e),
        };
        if let Some(what) = stopped {
            v.say(format!(
                "interrupted: {what}; {written} of {count} frames written"
            ));
            return Ok(Ending::Partial);
        }
    }
    let skipped = match skipped {
        0 => String::new(),
        n => format!(", {n} skipped as they exist"),
    };
    v.say(format!("{written} of {count} frames written{skipped}"));
    Ok(Ending::Complete)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range(s: &str) -> std::result::Result<(u32, u32), String> {
        s.parse::<FrameRange>().map(|r| (r.first, r.last))
    }

    #[test]
    fn frame_ranges_exclude_their_end_unless_it_is_included() {
        assert_eq!(range("0..3"), Ok((0, 2)));
        assert_eq!(range("5..6"), Ok((5, 5)));
        assert_eq!(range("0..=3"), Ok((0, 3)));
        assert_eq!(range("7..=7"), Ok((7, 7)));
        assert_eq!(range("12"), Ok((12, 12)));
        assert_eq!(range(" 1 .. 4 "), Ok((1, 3)));
        assert_eq!(range("0..4294967295"), Ok((0, u32::MAX - 1)));
        assert_eq!(range("0..=4294967295"), Ok((0, u32::MAX)));
        assert_eq!("0..=9".parse::<FrameRange>().unwrap().count(), 10);
    }

    #[test]
    fn bad_frame_ranges_say_what_is_wrong() {
        for empty in ["5..2", "3..3", "0..0", "4..=3"] {
            let e = range(empty).unwrap_err();
            assert!(e.contains("holds no frame"), "{empty}: {e}");
        }
        for bad in [
            "a..b",
            "..4",
            "2..",
            "-1..3",
            "1.5..3",
            "1...3",
            "",
            "x",
            "1..=",
            "4294967296",
        ] {
            let e = range(bad).unwrap_err();
            assert!(e.contains("is not a frame range"), "{bad}: {e}");
        }
    }

    fn pattern(s: &str) -> Result<Pattern> {
        Pattern::of("-o", Path::new(s))
    }

    #[test]
    fn patterns_print_the_frame_number_as_printf_does() {
        let p = |s: &str, frame| pattern(s).unwrap().path(frame);
        assert_eq!(p("out_%04d.png", 7), PathBuf::from("out_0007.png"));
        assert_eq!(p("out_%04d.png", 123456), PathBuf::from("out_123456.png"));
        assert_eq!(p("%d.png", 42), PathBuf::from("42.png"));
        assert_eq!(p("f/%02d/x.exr", 3), PathBuf::from("f/03/x.exr"));
        assert_eq!(p("100%%_%d.png", 5), PathBuf::from("100%_5.png"));
    }

    #[test]
    fn outputs_without_one_frame_number_are_refused() {
        let e = |s: &str| pattern(s).unwrap_err().to_string();
        assert!(e("out.png").contains("has none"), "{}", e("out.png"));
        assert!(e("100%%.png").contains("has none"));
        assert!(e("a%d_%04d.png").contains("2 frame numbers"));
        for stray in [
            "out_%4d.png",
            "out_%s.png",
            "out_%.png",
            "out_%",
            "%011d.png",
            "%x%d",
        ] {
            assert!(
                e(stray).contains("is no frame number"),
                "{stray}: {}",
                e(stray)
            );
        }
    }
}
