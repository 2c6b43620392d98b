//! Parsers of flag values that are more than a number or a name.

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

/// `--devices`: `all` (any case) is `None`, every device; otherwise the comma-separated
/// selectors, each trimmed.
pub fn device_list(flag: &str) -> Option<Vec<String>> {
    (!flag.trim().eq_ignore_ascii_case("all"))
        .then(|| flag.split(',').map(|s| s.trim().to_string()).collect())
}
