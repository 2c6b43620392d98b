//! `cltrace merge`: the parts of a render (`render --region/--samples`) into one image.
//! The sums are integers, so adding them is exact in any order: the merged image equals
//! the one-shot render of the same samples on the same device, bit for bit.

use std::path::PathBuf;

use rayon::prelude::*;

use super::Ending;
use crate::error::{Error, Result};
use crate::output;
use crate::output::part::{Part, read_part};
use crate::render::integrator::{Accumulation, Region};
use crate::render::{Frame, tone_map};
use crate::report::{Timings, Verbosity, format_ms};

/// Everything `cltrace merge` was asked to do.
#[derive(Clone, Debug, Default)]
pub struct MergeRequest {
    /// The parts, in any order.
    pub parts: Vec<PathBuf>,
    /// The image to write; its extension picks the format.
    pub output: PathBuf,
    /// How much goes to stderr.
    pub verbosity: Verbosity,
}

/// Reads the parts, checks that they fit together (the same settings, no pixel's sample
/// given twice, every pixel covered), adds them and writes the image.
pub fn merge(req: &MergeRequest) -> Result<Ending> {
    let start = std::time::Instant::now();
    let v = req.verbosity;
    if req.parts.is_empty() {
        return Err(Error::Invalid("merge needs at least one part".into()));
    }
    output::image_format(&req.output)?;
    let mut timings = Timings::default();
    let parts: Vec<Part> = timings.time("read", || {
        req.parts
            .par_iter()
            .map(|p| read_part(p))
            .collect::<Result<_>>()
    })?;
    crate::interrupt::check()?;
    let acc = timings.time("add", || add_parts(&req.parts, &parts))?;
    let counts: Vec<i64> = acc.pixels.iter().map(|p| p[3]).collect();
    let (lo, hi) = (
        counts.iter().copied().min().unwrap_or(0),
        counts.iter().copied().max().unwrap_or(0),
    );
    if lo != hi {
        v.say(format!(
            "warning: pixels hold {lo} to {hi} samples: a part is missing samples (an \
             interrupted render?) or the sample ranges differ between regions"
        ));
    }
    let shade = parts[0].shade;
    let (width, height) = acc.image_size();
    let mut frame = Frame::new(width, height);
    let radiance = timings.time("tone-map", || acc.radiance());
    frame.colors = tone_map(&radiance, shade);
    frame.radiance = Some(radiance);
    timings.time("write", || output::write_image(&frame, &req.output))?;
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    timings.close(wall_ms);
    v.say(format!(
        "wrote {} ({width}x{height}, {} parts, {lo} samples per pixel{})",
        req.output.display(),
        parts.len(),
        match lo == hi {
            true => String::new(),
            false => format!(" to {hi}"),
        }
    ));
    v.say(format!(
        "{}, total {}",
        timings.summary(),
        format_ms(wall_ms)
    ));
    Ok(Ending::Complete)
}

/// The parts added into one accumulation of the whole image, refused where they do not fit.
fn add_parts(paths: &[PathBuf], parts: &[Part]) -> Result<Accumulation> {
    let name = |i: usize| paths[i].display().to_string();
    let first = &parts[0];
    for (i, part) in parts.iter().enumerate().skip(1) {
        if let Some(why) = first.mismatch(part) {
            return Err(Error::Invalid(format!(
                "{} does not fit {}: a part of another render ({why})",
                name(i),
                name(0)
            )));
        }
    }
    // No pixel may get the same sample twice: a part given twice, or overlapping tiles.
    for i in 0..parts.len() {
        for j in i + 1..parts.len() {
            let (a, b) = (&parts[i], &parts[j]);
            let (ra, rb) = (a.accumulation.region, b.accumulation.region);
            let shared = a.samples.start < b.samples.end && b.samples.start < a.samples.end;
            if ra.overlaps(&rb) && shared {
                return Err(Error::Invalid(format!(
                    "{} and {} both hold samples {}..{} of pixels {}: a part given twice, \
                     or regions that overlap",
                    name(i),
                    name(j),
                    a.samples.start.max(b.samples.start),
                    a.samples.end.min(b.samples.end),
                    intersection(&ra, &rb)
                )));
            }
        }
    }
    let (width, height) = first.accumulation.image_size();
    let mut acc = Accumulation::new(width, height);
    for (i, part) in parts.iter().enumerate() {
        acc.add(&part.accumulation)
            .ok_or_else(|| Error::Invalid(format!("{}: the sums overflow", name(i))))?;
    }
    let empty = acc.pixels.iter().position(|p| p[3] == 0);
    if let Some(i) = empty {
        let missing = acc.pixels.iter().filter(|p| p[3] == 0).count();
        return Err(Error::Invalid(format!(
            "{missing} of the {width}x{height} pixels have no samples (the first at {},{}): \
             a part is missing",
            i % width as usize,
            i / width as usize
        )));
    }
    Ok(acc)
}

fn intersection(a: &Region, b: &Region) -> Region {
    Region {
        x0: a.x0.max(b.x0),
        y0: a.y0.max(b.y0),
        x1: a.x1.min(b.x1),
        y1: a.y1.min(b.y1),
    }
}
