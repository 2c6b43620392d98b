//! Parsers of flag values: the library's enums as possible values, vectors, resolutions,
//! device lists.

use std::ffi::OsStr;
use std::marker::PhantomData;
use std::str::FromStr;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use cltrace::bench::RayKind;
use cltrace::bvh::{Builder, Layout};
use cltrace::camera::{Projection, View};
use cltrace::output::HitsFormat;
use cltrace::render::{Method, Shade};

/// The value of a whole-number flag (a size, a count, a seed). Each flag's own range is
/// checked later, where the limit is known; this says only what is no whole number at all,
/// in words rather than as clap's `0..=4294967295`.
pub fn whole_number(s: &str) -> Result<u32, String> {
    let t = s.trim();
    t.parse::<u32>().map_err(|_| match t.parse::<i128>() {
        Ok(v) if v < 0 => format!("{s} is negative: give a whole number, 0 or more"),
        Ok(_) => format!("{s} is too large"),
        Err(_) if t.parse::<f64>().is_ok() => format!("{s} is not a whole number"),
        Err(_) => format!("`{s}` is not a number"),
    })
}

/// A triangle count: a whole number, or one with a suffix `k`, `M` or `G` (thousands,
/// millions, billions; `300M`, `2.5G`).
pub fn triangle_count(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (number, scale) = match t.char_indices().last() {
        Some((i, 'k' | 'K')) => (&t[..i], 1e3),
        Some((i, 'M')) => (&t[..i], 1e6),
        Some((i, 'G')) => (&t[..i], 1e9),
        _ => (t, 1.0),
    };
    match number.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 && (v * scale) < 1e15 && (v * scale).fract() == 0.0 => {
            Ok((v * scale) as u64)
        }
        _ => Err(format!(
            "`{s}` is not a triangle count: a whole number, or one with k, M or G (300M)"
        )),
    }
}

/// A library enum a flag chooses among: every value, its name on the command line (which
/// its `FromStr` reads back) and a line on it for `--help`.
pub trait Choice: Copy + FromStr<Err = String> + Send + Sync + 'static {
    const ALL: &'static [Self];
    fn name(self) -> &'static str;
    fn about(self) -> &'static str;
}

macro_rules! choices {
    ($($t:ty),* $(,)?) => {$(
        impl Choice for $t {
            const ALL: &'static [Self] = &<$t>::ALL;
            fn name(self) -> &'static str {
                <$t>::name(self)
            }
            fn about(self) -> &'static str {
                <$t>::about(self)
            }
        }
    )*};
}

choices!(
    Builder, Layout, Method, Shade, RayKind, View, Projection, HitsFormat
);

/// The value parser of a [`Choice`]: `--help` lists the names with their lines, and a value
/// that is none of them (or not UTF-8) is an "invalid value" error listing them, as for a
/// clap `ValueEnum`.
pub fn choice<T: Choice>() -> ChoiceParser<T> {
    ChoiceParser(PhantomData)
}

pub struct ChoiceParser<T>(PhantomData<fn() -> T>);

impl<T> Clone for ChoiceParser<T> {
    fn clone(&self) -> Self {
        ChoiceParser(PhantomData)
    }
}

impl<T: Choice> ChoiceParser<T> {
    fn possible() -> impl Iterator<Item = PossibleValue> {
        T::ALL
            .iter()
            .map(|v| PossibleValue::new(v.name()).help(v.about()))
    }
}

impl<T: Choice> TypedValueParser for ChoiceParser<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        // Not UTF-8: the lossy form (which no name matches) makes the same error as any
        // other unknown value.
        let value = value.to_string_lossy();
        let name = PossibleValuesParser::new(Self::possible()).parse_ref(
            cmd,
            arg,
            OsStr::new(value.as_ref()),
        )?;
        Ok(name.parse().expect("every possible value names one"))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(Self::possible()))
    }
}

/// The names of every value, comma-separated: the default of a flag that takes a list.
pub fn all_names<T: Choice>() -> String {
    T::ALL
        .iter()
        .map(|v| v.name())
        .collect::<Vec<_>>()
        .join(",")
}

/// `x,y,z`: three finite numbers.
pub fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<f32> = parts
        .iter()
        .map(|p| p.parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` is not three numbers `x,y,z`"))?;
    match numbers.as_slice() {
        [x, y, z] if numbers.iter().all(|v| v.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("`{s}` is not three finite numbers `x,y,z`")),
    }
}

/// `WIDTHxHEIGHT` (or `WIDTHXHEIGHT`).
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not a resolution `WIDTHxHEIGHT`"))?;
    match (w.trim().parse(), h.trim().parse()) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(format!("`{s}` is not a resolution `WIDTHxHEIGHT`")),
    }
}

/// A work-group shape `WxH`, each side at least 1 (whether the device can run it is the
/// device's to say).
pub fn parse_work_group(s: &str) -> Result<[usize; 2], String> {
    match parse_resolution(s) {
        Ok((w, h)) if w > 0 && h > 0 => Ok([w as usize, h as usize]),
        _ => Err(format!(
            "`{s}` is not a work-group shape `WxH` of positive sizes"
        )),
    }
}

/// `--devices`: `all` (any case) is `None`, every device; otherwise the comma-separated
/// selectors, each trimmed.
pub fn device_list(flag: &str) -> Option<Vec<String>> {
    (!flag.trim().eq_ignore_ascii_case("all"))
        .then(|| flag.split(',').map(|s| s.trim().to_string()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_group_shapes_take_two_positive_sides() {
        assert_eq!(parse_work_group("16x8"), Ok([16, 8]));
        assert_eq!(parse_work_group("3X5"), Ok([3, 5]));
        for bad in ["0x8", "8x0", "8", "8x", "-1x8", "axb"] {
            assert!(parse_work_group(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn triangle_counts_take_k_m_and_g() {
        assert_eq!(triangle_count("300M"), Ok(300_000_000));
        assert_eq!(triangle_count("2.5G"), Ok(2_500_000_000));
        assert_eq!(triangle_count(" 10k "), Ok(10_000));
        assert_eq!(triangle_count("12345"), Ok(12_345));
        for bad in ["", "M", "-1M", "1.5", "ten", "1e300", "3T"] {
            assert!(triangle_count(bad).is_err(), "{bad}");
        }
    }
}
