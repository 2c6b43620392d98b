//! Parts of a render: the per-pixel fixed-point radiance sums and sample counts of a region
//! of the image over a range of sample indices, kept in an OpenEXR file so that nothing is
//! lost between `render --region/--samples` and `cltrace merge`.
//!
//! The file's display window is the whole image and its data window the region. Channels:
//! `R`, `G`, `B` (16-bit float, the mean radiance, for any EXR viewer), and the exact sums
//! as 32-bit unsigned halves, `sum.R.hi`, `sum.R.lo` and so on for G and B, with the sample
//! count in `samples` and the rays traced in `rays`. Attributes: `cltrace.settings` (the
//! scene's content hash, camera, resolution and shading that every part of one render
//! shares), `cltrace.fingerprint` (a hash of them), `cltrace.samples` (`FIRST..END`),
//! `cltrace.shade` and `cltrace.version`.

use std::ops::Range;
use std::path::Path;

use exr::prelude::*;

use crate::error::{Error, Result};
use crate::render::Shade;
use crate::render::integrator::{Accumulation, Region};

/// The sums' channels, in the order of an accumulation pixel's lanes.
const SUM_CHANNELS: [&str; 3] = ["R", "G", "B"];
const SETTINGS: &str = "cltrace.settings";
const FINGERPRINT: &str = "cltrace.fingerprint";
const SAMPLES: &str = "cltrace.samples";
const SHADE: &str = "cltrace.shade";
const VERSION: &str = "cltrace.version";

/// One part of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The sums and counts of the part's region.
    pub accumulation: Accumulation,
    /// The sample indices asked for (a pixel's count says how many it got: fewer when the
    /// render was interrupted).
    pub samples: Range<u32>,
    /// What every part of one render shares, as `key=value` lines: scene, camera,
    /// resolution, shading.
    pub settings: String,
    /// How the merged radiance is turned into colours.
    pub shade: Shade,
}

impl Part {
    /// A hash of the settings, shown in errors and kept in the file.
    pub fn fingerprint(&self) -> String {
        format!("{:016x}", crate::hash::fnv1a(self.settings.as_bytes()))
    }

    /// Why `other` cannot be merged with `self` (named `mine` and `theirs` in the message),
    /// or `None` when they fit together: the first setting that differs.
    pub fn mismatch(&self, other: &Part) -> Option<String> {
        if self.settings == other.settings && self.shade == other.shade {
            return None;
        }
        let theirs: Vec<&str> = other.settings.lines().collect();
        for (i, line) in self.settings.lines().enumerate() {
            let other_line = theirs.get(i).copied().unwrap_or("(nothing)");
            if line != other_line {
                return Some(format!("`{other_line}` where the first part has `{line}`"));
            }
        }
        Some(format!(
            "settings {} where the first part has {}",
            other.fingerprint(),
            self.fingerprint()
        ))
    }
}

/// Writes `part` to `path` atomically (see [`super::write_atomically`]).
pub fn write_part(part: &Part, path: &Path) -> Result<()> {
    let acc = &part.accumulation;
    let r = acc.region;
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let radiance = acc.radiance();
    for (c, name) in SUM_CHANNELS.iter().enumerate() {
        channels.push(AnyChannel::new(
            *name,
            FlatSamples::F16(radiance.iter().map(|p| f16::from_f32(p[c])).collect()),
        ));
        let sums = || acc.pixels.iter().map(|p| p[c] as u64);
        channels.push(AnyChannel::new(
            format!("sum.{name}.hi").as_str(),
            FlatSamples::U32(sums().map(|s| (s >> 32) as u32).collect()),
        ));
        channels.push(AnyChannel::new(
            format!("sum.{name}.lo").as_str(),
            FlatSamples::U32(sums().map(|s| s as u32).collect()),
        ));
    }
    channels.push(AnyChannel::new(
        "samples",
        FlatSamples::U32(acc.pixels.iter().map(|p| p[3] as u32).collect()),
    ));
    // The rays of the whole part sit in its first pixel's `rays`: per-pixel ray counts are
    // not kept on the device past the sum.
    let mut rays = vec![0u32; acc.pixels.len()];
    let (hi, lo) = ((acc.rays >> 32) as u32, acc.rays as u32);
    rays[0] = lo;
    if rays.len() > 1 {
        rays[1] = hi;
    }
    channels.push(AnyChannel::new("rays", FlatSamples::U32(rays)));

    let mut attributes = LayerAttributes {
        layer_position: Vec2(r.x0 as i32, r.y0 as i32),
        ..LayerAttributes::default()
    };
    let text = |s: &str| AttributeValue::Text(Text::from(s));
    for (key, value) in [
        (SETTINGS, part.settings.clone()),
        (FINGERPRINT, part.fingerprint()),
        (
            SAMPLES,
            format!("{}..{}", part.samples.start, part.samples.end),
        ),
        (SHADE, part.shade.name().to_string()),
        (VERSION, env!("CARGO_PKG_VERSION").to_string()),
    ] {
        attributes.other.insert(Text::from(key), text(&value));
    }
    let layer = Layer::new(
        (r.width() as usize, r.height() as usize),
        attributes,
        // ZIP: an eighth of RLE's size on a 1080p part, for half again its write time.
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let image = Image::new(
        ImageAttributes::new(IntegerBounds::from_dimensions((
            acc.width as usize,
            acc.height as usize,
        ))),
        layer,
    );
    super::write_atomically(path, |w| {
        image
            .write()
            .to_buffered(w)
            .map_err(|e| Error::output(path, e))
    })
}

/// Reads a part written by [`write_part`]. Anything else (not EXR, an EXR without the
/// attributes or channels, counts or sums that cannot be) is a clear error.
pub fn read_part(path: &Path) -> Result<Part> {
    let bad = |why: String| Error::Invalid(format!("{}: {why}", path.display()));
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| match e {
            exr::error::Error::Io(io) => Error::Input {
                path: path.to_path_buf(),
                line: None,
                message: io.to_string(),
            },
            e => bad(format!("not a readable OpenEXR file ({e})")),
        })?;
    let layer = &image.layer_data;
    let other = &layer.attributes.other;
    let attribute = |key: &str| match other.get(&Text::from(key)) {
        Some(AttributeValue::Text(t)) => Ok(t.to_string()),
        _ => Err(bad(format!(
            "not a part of a cltrace render (no `{key}` attribute): write parts with \
             `cltrace render --region` or `--samples`"
        ))),
    };
    let settings = attribute(SETTINGS)?;
    let shade: Shade = attribute(SHADE)?
        .parse()
        .map_err(|e: String| bad(format!("its shade: {e}")))?;
    let samples = attribute(SAMPLES)?;
    let samples = crate::render::integrator::parse_sample_range(&samples)
        .map_err(|e| bad(format!("its sample range: {e}")))?;

    let display = image.attributes.display_window;
    if display.position != Vec2(0, 0) {
        return Err(bad("its display window does not start at 0,0".into()));
    }
    let (width, height) = (display.size.0 as u32, display.size.1 as u32);
    let Vec2(x0, y0) = layer.attributes.layer_position;
    let Vec2(w, h) = layer.size;
    let region = Region {
        x0: x0.max(0) as u32,
        y0: y0.max(0) as u32,
        x1: x0.max(0) as u32 + w as u32,
        y1: y0.max(0) as u32 + h as u32,
    };
    if x0 < 0 || y0 < 0 || region.x1 > width || region.y1 > height || w == 0 || h == 0 {
        return Err(bad(format!(
            "its data window ({region}) is not inside its {width}x{height} image"
        )));
    }
    let channel = |name: &str| -> Result<&[u32]> {
        match layer.channel_data.list.iter().find(|c| c.name == *name) {
            Some(AnyChannel {
                sample_data: FlatSamples::U32(v),
                ..
            }) if v.len() == w * h => Ok(v),
            _ => Err(bad(format!("no `{name}` channel of 32-bit integers"))),
        }
    };
    let mut acc = Accumulation::of_region(width, height, region);
    for (c, name) in SUM_CHANNELS.iter().enumerate() {
        let hi = channel(&format!("sum.{name}.hi"))?;
        let lo = channel(&format!("sum.{name}.lo"))?;
        for (p, (&hi, &lo)) in acc.pixels.iter_mut().zip(hi.iter().zip(lo)) {
            let sum = ((hi as u64) << 32) | lo as u64;
            p[c] = i64::try_from(sum).map_err(|_| bad("a radiance sum out of range".into()))?;
        }
    }
    for (p, &n) in acc.pixels.iter_mut().zip(channel("samples")?) {
        p[3] = n as i64;
    }
    let rays = channel("rays")?;
    acc.rays = rays[0] as u64 | (rays.get(1).copied().unwrap_or(0) as u64) << 32;
    let part = Part {
        accumulation: acc,
        samples,
        settings,
        shade,
    };
    if attribute(FINGERPRINT)? != part.fingerprint() {
        return Err(bad(
            "its settings do not match its fingerprint: the file was edited or damaged".into(),
        ));
    }
    Ok(part)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part() -> Part {
        let mut acc = Accumulation::of_region(
            7,
            5,
            Region {
                x0: 2,
                y0: 1,
                x1: 6,
                y1: 4,
            },
        );
        for (i, p) in acc.pixels.iter_mut().enumerate() {
            // Sums above 2^32 and below, so both halves of each are exercised.
            *p = [(i as i64) << 33 | 5, i as i64 * 3, 1 << 40, 4 + i as i64];
        }
        acc.rays = (1 << 35) + 17;
        Part {
            accumulation: acc,
            samples: 4..8,
            settings: "scene=1\nimage=7x5\nseed=3".into(),
            shade: Shade::Path,
        }
    }

    #[test]
    fn a_part_reads_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.exr");
        let p = part();
        write_part(&p, &path).unwrap();
        assert_eq!(read_part(&path).unwrap(), p);
    }

    #[test]
    fn a_mismatch_names_the_first_setting_that_differs() {
        let (a, mut b) = (part(), part());
        assert_eq!(a.mismatch(&b), None);
        b.settings = "scene=1\nimage=7x5\nseed=4".into();
        let why = a.mismatch(&b).unwrap();
        assert!(
            why.contains("`seed=4`") && why.contains("`seed=3`"),
            "{why}"
        );
        assert_ne!(a.fingerprint(), b.fingerprint());
    }
}
