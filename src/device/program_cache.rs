//! Compiled programs kept between runs, so that a second render does not compile: one file
//! per program in the user's cache folder, named by a hash of everything the binary
//! depends on (cltrace's version, the device, its driver and OpenCL C version, the
//! drivers' compiler settings in the environment, the build options and the source). An
//! entry holds that key in full and a checksum of itself, so a hash collision, a truncated
//! or a corrupt file reads as a miss and is rebuilt; entries are written atomically. The
//! cache is an optimisation: no failure of it fails a render.

use crate::hash::fnv1a;
use std::ffi::OsString;
use std::path::PathBuf;

use super::DeviceInfo;

/// The first line of every entry; a new format gets a new number.
const MAGIC: &[u8] = b"cltrace program cache 1\n";

/// The cache folder: `CLTRACE_KERNEL_CACHE` (`off` for none), else
/// `$XDG_CACHE_HOME/cltrace/kernels`, else `~/.cache/cltrace/kernels`.
pub fn default_folder() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CLTRACE_KERNEL_CACHE") {
        return (p != "off" && !p.is_empty()).then(|| PathBuf::from(p));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("cltrace").join("kernels"))
}

/// What the cache did for one program, for `render -v` and `--json`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CacheUse {
    /// The program was loaded from this entry; nothing was compiled.
    Hit(PathBuf),
    /// Compiled, and saved to this entry for the next run.
    Stored(PathBuf),
    /// The entry could not be used (corrupt, another key, refused by the driver): it was
    /// ignored, the program compiled and the entry written again.
    Replaced(PathBuf, String),
    /// Compiled, but not saved (the reason).
    NotStored(String),
}

impl CacheUse {
    /// Whether the program came from the cache.
    pub fn hit(&self) -> bool {
        matches!(self, CacheUse::Hit(_))
    }

    /// One line for `render -v`.
    pub fn describe(&self) -> String {
        match self {
            CacheUse::Hit(p) => format!("program cache: hit, {}", p.display()),
            CacheUse::Stored(p) => format!("program cache: compiled, saved to {}", p.display()),
            CacheUse::Replaced(p, why) => format!(
                "program cache: ignored {} ({why}); compiled and saved again",
                p.display()
            ),
            CacheUse::NotStored(why) => format!("program cache: compiled, not saved ({why})"),
        }
    }
}

/// The cache in one folder.
#[derive(Clone, Debug)]
pub(crate) struct ProgramCache {
    folder: PathBuf,
}

/// One program's place in the cache: its full key and its file.
pub(crate) struct Entry {
    key: Vec<u8>,
    pub(crate) path: PathBuf,
}

impl ProgramCache {
    pub(crate) fn new(folder: PathBuf) -> Self {
        ProgramCache { folder }
    }

    /// The entry of the program built from `source` with `options` for `device`.
    pub(crate) fn entry(&self, device: &DeviceInfo, options: &str, source: &str) -> Entry {
        let key = format!(
            "cltrace {}\n{}\n{}\n{}{options}\nsource {} bytes, fnv1a {:016x}\n",
            env!("CARGO_PKG_VERSION"),
            device.key(),
            device.opencl_c_version,
            compiler_settings(std::env::vars_os()),
            source.len(),
            fnv1a(source.as_bytes()),
        )
        .into_bytes();
        let path = self.folder.join(format!("{:016x}.bin", fnv1a(&key)));
        Entry { key, path }
    }
}

impl Entry {
    /// The stored binary; `Err` with the reason when the file exists but cannot be used,
    /// `Ok(None)` when there is none.
    pub(crate) fn load(&self) -> Result<Option<Vec<u8>>, String> {
        let bytes = match std::fs::read(&self.path) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e.to_string()),
        };
        parse(&bytes, &self.key).map(Some)
    }

    /// Saves `binary` under this entry, atomically (the folder is made if needed).
    pub(crate) fn store(&self, binary: &[u8]) -> Result<(), String> {
        let bytes = encode(&self.key, binary);
        if let Some(folder) = self.path.parent() {
            std::fs::create_dir_all(folder).map_err(|e| e.to_string())?;
        }
        crate::output::write_atomically(&self.path, |w| {
            use std::io::Write;
            w.write_all(&bytes)
                .map_err(|e| crate::Error::output(&self.path, e))
        })
        .map_err(|e| e.to_string())
    }
}

/// The variables of `environment` through which the drivers take compiler settings, one
/// `name=value` line each, sorted: Intel's CPU runtime's `CL_CONFIG_*`
/// (`CL_CONFIG_USE_VECTORIZER` changes the code it builds) and PoCL's `POCL_*`. Without
/// them a binary built under one setting served another.
fn compiler_settings(environment: impl Iterator<Item = (OsString, OsString)>) -> String {
    let mut lines: Vec<String> = environment
        .map(|(name, value)| (name.to_string_lossy().into_owned(), value))
        .filter(|(name, _)| name.starts_with("CL_CONFIG_") || name.starts_with("POCL_"))
        .map(|(name, value)| format!("{name}={}\n", value.to_string_lossy()))
        .collect();
    lines.sort();
    lines.concat()
}

/// An entry's bytes: the magic line, the key and the binary (each after its length), then
/// the checksum of all before it.
fn encode(key: &[u8], binary: &[u8]) -> Vec<u8> {
    let mut bytes = MAGIC.to_vec();
    for part in [key, binary] {
        bytes.extend_from_slice(&(part.len() as u64).to_le_bytes());
        bytes.extend_from_slice(part);
    }
    bytes.extend_from_slice(&fnv1a(&bytes).to_le_bytes());
    bytes
}

/// The binary of an entry's bytes, checked against `key` and the checksum.
fn parse(bytes: &[u8], key: &[u8]) -> Result<Vec<u8>, String> {
    let corrupt = || "a corrupt entry".to_string();
    let body = bytes.strip_prefix(MAGIC).ok_or_else(corrupt)?;
    let (body, sum) = body
        .split_at_checked(body.len().checked_sub(8).ok_or_else(corrupt)?)
        .ok_or_else(corrupt)?;
    let whole = &bytes[..bytes.len() - 8];
    if u64::from_le_bytes(sum.try_into().expect("8 bytes")) != fnv1a(whole) {
        return Err(corrupt());
    }
    let mut rest = body;
    let mut part = || -> Result<&[u8], String> {
        let (len, tail) = rest.split_at_checked(8).ok_or_else(corrupt)?;
        let len = usize::try_from(u64::from_le_bytes(len.try_into().expect("8 bytes")))
            .map_err(|_| corrupt())?;
        let (part, tail) = tail.split_at_checked(len).ok_or_else(corrupt)?;
        rest = tail;
        Ok(part)
    };
    if part()? != key {
        return Err("an entry of another program with the same hash".into());
    }
    let binary = part()?.to_vec();
    if binary.is_empty() {
        return Err(corrupt());
    }
    Ok(binary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The drivers' compiler settings are part of the key, in any order; other variables
    /// are not.
    #[test]
    fn the_drivers_compiler_settings_key_the_entry() {
        let env = |vars: &[(&str, &str)]| {
            compiler_settings(
                vars.iter()
                    .map(|(n, v)| (OsString::from(n), OsString::from(v))),
            )
        };
        let on = env(&[
            ("HOME", "/h"),
            ("CL_CONFIG_USE_VECTORIZER", "True"),
            ("POCL_DEVICES", "pthread"),
        ]);
        assert_eq!(on, "CL_CONFIG_USE_VECTORIZER=True\nPOCL_DEVICES=pthread\n");
        assert_eq!(
            on,
            env(&[
                ("POCL_DEVICES", "pthread"),
                ("CL_CONFIG_USE_VECTORIZER", "True")
            ])
        );
        assert_ne!(
            on,
            env(&[
                ("CL_CONFIG_USE_VECTORIZER", "False"),
                ("POCL_DEVICES", "pthread")
            ])
        );
        assert_eq!(env(&[("HOME", "/h"), ("PATH", "/bin")]), "");
    }

    #[test]
    fn an_entry_reads_back_and_any_damage_is_refused() {
        let bytes = encode(b"key", b"binary");
        assert_eq!(parse(&bytes, b"key").unwrap(), b"binary");
        assert!(parse(&bytes, b"other key").is_err());
        // Every truncation and every flipped byte is caught, never a panic.
        for len in 0..bytes.len() {
            assert!(parse(&bytes[..len], b"key").is_err(), "truncated to {len}");
        }
        for i in 0..bytes.len() {
            let mut damaged = bytes.clone();
            damaged[i] ^= 0x40;
            assert!(parse(&damaged, b"key").is_err(), "byte {i} flipped");
        }
        assert!(parse(&encode(b"key", b""), b"key").is_err());
    }
}
