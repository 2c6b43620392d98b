//! OpenCL devices: listing every platform and device, choosing one (`--device`,
//! `CLTRACE_DEVICE`), and opening it with a profiling queue.

mod pitched;
mod program;
mod program_cache;
pub mod tracer;

pub(crate) use pitched::PitchedBuffer;
pub use program::{Constant, Program, shared_constants};
pub use program_cache::{CacheUse, default_folder as program_cache_folder};
pub use tracer::{ClTracer, Kernel, Kernels, tile_entries_parameters};

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use ocl::core::{DeviceInfo as Info, DeviceInfoResult as R, DeviceType};

use crate::bvh::Layout;
use crate::error::{Error, Result};

macro_rules! ocl_prm {
    ($($t:ty),*) => {$(
        // SAFETY: plain-old-data with a fixed C layout, mirrored in the kernels
        // (tests/layout.rs compares the two).
        unsafe impl ocl::OclPrm for $t {}
    )*};
}
ocl_prm!(
    crate::intersect::Triangle,
    crate::bvh::Bin32Node,
    crate::render::Hit,
    crate::material::Material,
    crate::material::texture::TextureInfo
);

/// The layout for a device nobody has tuned: wide nodes for CPUs (their boxes go through
/// SIMD lanes), Aila–Laine binary nodes elsewhere (the fastest for primary and diffuse rays
/// on the H100: docs/performance.md).
pub fn default_layout(device: &DeviceInfo) -> Layout {
    device.kind.default_layout()
}

impl DeviceKind {
    /// The layout for an untuned device of this kind (see [`default_layout`]).
    pub fn default_layout(self) -> Layout {
        match self {
            DeviceKind::Cpu => Layout::Wide8,
            _ => Layout::Bin64,
        }
    }
}

/// How to get an OpenCL device on Debian or Ubuntu; part of every "no device" error.
pub(crate) const INSTALL_HINT: &str = "install an OpenCL driver, e.g. PoCL for the CPU: \
     `apt-get install pocl-opencl-icd ocl-icd-opencl-dev` (or your GPU vendor's OpenCL driver)";

/// The kind of a device, as OpenCL reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceKind {
    /// `CL_DEVICE_TYPE_GPU`.
    Gpu,
    /// `CL_DEVICE_TYPE_CPU`: the host's cores, through a driver such as PoCL.
    Cpu,
    /// `CL_DEVICE_TYPE_ACCELERATOR`.
    Accelerator,
    /// Any other type (custom devices).
    Other,
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DeviceKind::Gpu => "gpu",
            DeviceKind::Cpu => "cpu",
            DeviceKind::Accelerator => "accelerator",
            DeviceKind::Other => "other",
        })
    }
}

/// One OpenCL device and what cltrace needs to know about it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub(crate) platform_index: usize,
    pub(crate) device_index: usize,
    pub(crate) platform_name: String,
    /// `CL_DEVICE_NAME`, trimmed.
    pub name: String,
    pub(crate) kind: DeviceKind,
    pub(crate) compute_units: u32,
    /// `CL_DEVICE_GLOBAL_MEM_SIZE`, in bytes.
    pub global_memory: u64,
    /// `CL_DEVICE_MAX_MEM_ALLOC_SIZE`: the largest single buffer, in bytes.
    pub max_allocation: u64,
    /// `CL_DEVICE_MAX_WORK_GROUP_SIZE`: the most work-items in a work-group.
    pub max_work_group_size: usize,
    pub(crate) opencl_c_version: String,
    pub(crate) driver_version: String,
    /// `CL_DEVICE_MEM_BASE_ADDR_ALIGN`, in bytes.
    pub(crate) base_address_alignment: usize,
    /// Whether `-cl-fp32-correctly-rounded-divide-sqrt` is honoured.
    pub(crate) correctly_rounded_divide: bool,
    /// Whether NVIDIA's `-cl-nv-*` build options are taken (`cl_nv_compiler_options`).
    pub(crate) nv_compiler_options: bool,
    pub(crate) platform: ocl::Platform,
    pub(crate) device: ocl::Device,
}

impl DeviceInfo {
    /// `P:D`, the index `--device` accepts.
    pub fn index(&self) -> String {
        format!("{}:{}", self.platform_index, self.device_index)
    }

    /// `CL_PLATFORM_NAME` of the device's platform, trimmed: which OpenCL implementation
    /// drives it ("Portable Computing Language", "Intel(R) OpenCL", ...).
    pub fn platform_name(&self) -> &str {
        &self.platform_name
    }

    /// What identifies the device across runs (and cache files): platform, name, driver.
    pub fn key(&self) -> String {
        format!(
            "{} / {} / {}",
            self.platform_name, self.name, self.driver_version
        )
    }

    /// Row alignment of pitched output buffers: the device's base address alignment, and
    /// never less than 256 bytes.
    pub(crate) fn pitch_alignment(&self) -> usize {
        self.base_address_alignment.max(256)
    }

    fn read(
        platform_index: usize,
        platform: ocl::Platform,
        device_index: usize,
        device: ocl::Device,
    ) -> Result<Self> {
        let info = |what: Info| {
            ocl::core::get_device_info(device, what).map_err(|e| {
                Error::Device(format!(
                    "cannot query OpenCL device {platform_index}:{device_index}: {e}"
                ))
            })
        };
        let name = match info(Info::Name)? {
            R::Name(s) => s.trim().to_string(),
            _ => String::new(),
        };
        let kind = match info(Info::Type)? {
            R::Type(t) if t.contains(DeviceType::GPU) => DeviceKind::Gpu,
            R::Type(t) if t.contains(DeviceType::CPU) => DeviceKind::Cpu,
            R::Type(t) if t.contains(DeviceType::ACCELERATOR) => DeviceKind::Accelerator,
            _ => DeviceKind::Other,
        };
        let number = |r: R| -> u64 {
            match r {
                R::MaxComputeUnits(v) | R::MemBaseAddrAlign(v) => v as u64,
                R::GlobalMemSize(v) | R::MaxMemAllocSize(v) => v,
                R::MaxWorkGroupSize(v) => v as u64,
                _ => 0,
            }
        };
        let correctly_rounded_divide = matches!(info(Info::SingleFpConfig)?,
            R::SingleFpConfig(c) if c.contains(ocl::core::DeviceFpConfig::CORRECTLY_ROUNDED_DIVIDE_SQRT));
        Ok(DeviceInfo {
            platform_index,
            device_index,
            platform_name: platform.name().unwrap_or_default().trim().to_string(),
            name,
            kind,
            compute_units: number(info(Info::MaxComputeUnits)?) as u32,
            global_memory: number(info(Info::GlobalMemSize)?),
            max_allocation: number(info(Info::MaxMemAllocSize)?),
            max_work_group_size: number(info(Info::MaxWorkGroupSize)?) as usize,
            opencl_c_version: match info(Info::OpenclCVersion)? {
                R::OpenclCVersion(s) => s.trim().to_string(),
                _ => String::new(),
            },
            driver_version: match info(Info::DriverVersion)? {
                R::DriverVersion(s) => s.trim().to_string(),
                _ => String::new(),
            },
            base_address_alignment: (number(info(Info::MemBaseAddrAlign)?) / 8) as usize,
            correctly_rounded_divide,
            nv_compiler_options: match info(Info::Extensions)? {
                R::Extensions(s) => s.split_whitespace().any(|e| e == "cl_nv_compiler_options"),
                _ => false,
            },
            platform,
            device,
        })
    }
}

impl fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} ({}, {} compute units, {})",
            self.index(),
            self.name,
            self.kind,
            self.compute_units,
            self.platform_name
        )
    }
}

/// Every device of every platform, in platform then device order. The list is read once
/// per process, under a lock: some drivers (PoCL among them) report no devices when two
/// threads initialise them at the same moment.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    static FOUND: std::sync::Mutex<Option<Vec<DeviceInfo>>> = std::sync::Mutex::new(None);
    let mut found = FOUND
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some(devices) = found.as_ref() {
        return Ok(devices.clone());
    }
    let devices = discover_devices()?;
    if !devices.is_empty() {
        *found = Some(devices.clone());
    }
    Ok(devices)
}

fn discover_devices() -> Result<Vec<DeviceInfo>> {
    // Ask for the count first: ocl's own listing sleeps ten seconds before it gives up
    // when no platform is installed.
    let mut count: ocl::core::ffi::cl_uint = 0;
    let status = unsafe { ocl::core::ffi::clGetPlatformIDs(0, std::ptr::null_mut(), &mut count) };
    if status != 0 || count == 0 {
        return Err(Error::Device(format!(
            "no OpenCL platform found: {INSTALL_HINT}"
        )));
    }
    let platforms = ocl::core::get_platform_ids()
        .map_err(|e| Error::Device(format!("cannot list OpenCL platforms: {e}")))?;
    let mut devices = Vec::new();
    for (p, id) in platforms.into_iter().enumerate() {
        let platform = ocl::Platform::new(id);
        // A platform without devices (or a broken one) is listed as having none.
        let ids = ocl::Device::list(platform, Some(DeviceType::ALL)).unwrap_or_default();
        for (d, device) in ids.into_iter().enumerate() {
            devices.push(DeviceInfo::read(p, platform, d, device)?);
        }
    }
    Ok(devices)
}

/// Which device to use, as `--device` or `CLTRACE_DEVICE` says it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSelector {
    /// The first GPU, else the first device.
    Default,
    /// `P:D`: platform P, device D.
    Index(usize, usize),
    /// `gpu`, `cpu` or `accelerator`: the first device of that kind.
    Kind(DeviceKind),
    /// Any other text: the first device whose name or platform name contains it, ignoring case.
    Name(String),
    /// `all`: every device (in a list for `render --device`; alone, the default device).
    All,
}

impl FromStr for DeviceSelector {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let s = s.trim();
        if s.is_empty() {
            return Err(Error::Invalid("empty device selector".into()));
        }
        if let Some((p, d)) = s.split_once(':')
            && let (Ok(p), Ok(d)) = (p.parse(), d.parse())
        {
            return Ok(DeviceSelector::Index(p, d));
        }
        Ok(match s.to_ascii_lowercase().as_str() {
            "default" => DeviceSelector::Default,
            "gpu" => DeviceSelector::Kind(DeviceKind::Gpu),
            "cpu" => DeviceSelector::Kind(DeviceKind::Cpu),
            "accelerator" => DeviceSelector::Kind(DeviceKind::Accelerator),
            "all" => DeviceSelector::All,
            _ => DeviceSelector::Name(s.to_string()),
        })
    }
}

impl DeviceSelector {
    /// The selector from `--device` if given, else from `CLTRACE_DEVICE`, else the default.
    pub fn from_flag_or_env(flag: Option<&str>) -> Result<Self> {
        match flag {
            Some(s) => s.parse(),
            None => match std::env::var("CLTRACE_DEVICE") {
                Ok(s) if !s.trim().is_empty() => s.parse(),
                _ => Ok(DeviceSelector::Default),
            },
        }
    }

    /// The device this selector names among `devices`.
    pub fn pick<'a>(&self, devices: &'a [DeviceInfo]) -> Result<&'a DeviceInfo> {
        if devices.is_empty() {
            return Err(Error::Device(format!(
                "no OpenCL device found: {INSTALL_HINT}"
            )));
        }
        let found = match self {
            DeviceSelector::Default | DeviceSelector::All => devices
                .iter()
                .find(|d| d.kind == DeviceKind::Gpu)
                .or(devices.first()),
            DeviceSelector::Index(p, d) => devices
                .iter()
                .find(|x| x.platform_index == *p && x.device_index == *d),
            DeviceSelector::Kind(k) => devices.iter().find(|d| d.kind == *k),
            DeviceSelector::Name(n) => {
                let n = n.to_lowercase();
                devices.iter().find(|d| {
                    d.name.to_lowercase().contains(&n)
                        || d.platform_name.to_lowercase().contains(&n)
                })
            }
        };
        found.ok_or_else(|| {
            let have: Vec<String> = devices.iter().map(|d| format!("{} {}", d.index(), d.name)).collect();
            Error::Device(format!(
                "no OpenCL device matches `{}` (devices: {}); see `cltrace devices`, or {INSTALL_HINT}",
                self.describe(),
                have.join(", ")
            ))
        })
    }

    fn describe(&self) -> String {
        match self {
            DeviceSelector::Default => "default".into(),
            DeviceSelector::Index(p, d) => format!("{p}:{d}"),
            DeviceSelector::Kind(k) => k.to_string(),
            DeviceSelector::Name(n) => n.clone(),
            DeviceSelector::All => "all".into(),
        }
    }

    /// A comma-separated list of selectors (`gpu,cpu`, `0:0,1:0`, `all`), from `--device`
    /// if given, else from `CLTRACE_DEVICE`, else the default device alone.
    pub fn list_from_flag_or_env(flag: Option<&str>) -> Result<Vec<Self>> {
        let text = match flag {
            Some(s) => s.to_string(),
            None => match std::env::var("CLTRACE_DEVICE") {
                Ok(s) if !s.trim().is_empty() => s,
                _ => return Ok(vec![DeviceSelector::Default]),
            },
        };
        text.split(',').map(str::parse).collect()
    }

    /// The devices a list of selectors names among `devices`, in order, each once: `all`
    /// is every device.
    pub fn pick_each<'a>(list: &[Self], devices: &'a [DeviceInfo]) -> Result<Vec<&'a DeviceInfo>> {
        let mut picked: Vec<&DeviceInfo> = Vec::new();
        for selector in list {
            let found = match selector {
                DeviceSelector::All if !devices.is_empty() => devices.iter().collect(),
                s => vec![s.pick(devices)?],
            };
            for d in found {
                if !picked.iter().any(|p| p.index() == d.index()) {
                    picked.push(d);
                }
            }
        }
        Ok(picked)
    }
}

/// An opened device: its context and an in-order queue with profiling, so that kernel
/// times come from the device's own clock.
pub struct ClDevice {
    /// The device this was opened from.
    pub info: DeviceInfo,
    pub(crate) context: ocl::Context,
    /// The in-order, profiling queue every command of this device goes to.
    pub queue: ocl::Queue,
    /// Programs built in this context, by build options and source: a second build of the
    /// same program is taken from here ([`ClDevice::build_source`]).
    pub(crate) programs: std::sync::Mutex<program::BuiltPrograms>,
    /// Where compiled tracing programs are kept between runs; `None` compiles every time.
    pub(crate) program_cache: Option<program_cache::ProgramCache>,
}

impl ClDevice {
    /// Lists the devices and opens the one `selector` names.
    pub fn select(selector: &DeviceSelector) -> Result<Self> {
        let devices = list_devices()?;
        Self::open(selector.pick(&devices)?.clone())
    }

    /// Lists the devices and opens each one `list` names, at once (a GPU driver takes a
    /// few hundred milliseconds to open).
    pub fn select_each(list: &[DeviceSelector]) -> Result<Vec<Self>> {
        let devices = list_devices()?;
        let picked = DeviceSelector::pick_each(list, &devices)?;
        std::thread::scope(|s| {
            let opening: Vec<_> = picked
                .iter()
                .map(|&info| s.spawn(move || Self::open(info.clone())))
                .collect();
            opening
                .into_iter()
                .map(|h| h.join().expect("opening a device does not panic"))
                .collect()
        })
    }

    pub(crate) fn open(info: DeviceInfo) -> Result<Self> {
        let fail = |e: ocl::Error| {
            Error::Device(format!(
                "cannot open OpenCL device {}: {}",
                info.index(),
                first_line(&e.to_string())
            ))
        };
        let context = ocl::Context::builder()
            .platform(info.platform)
            .devices(info.device)
            .build()
            .map_err(fail)?;
        let queue = ocl::Queue::new(
            &context,
            info.device,
            Some(ocl::flags::CommandQueueProperties::PROFILING_ENABLE),
        )
        .map_err(fail)?;
        crate::interrupt::reclaim_handlers();
        Ok(ClDevice {
            info,
            context,
            queue,
            programs: Default::default(),
            program_cache: None,
        })
    }

    /// Keeps compiled tracing programs in `folder` between runs (see
    /// [`program_cache_folder`]), so that a second run loads them instead of compiling.
    pub fn use_program_cache(&mut self, folder: PathBuf) {
        self.program_cache = Some(program_cache::ProgramCache::new(folder));
    }

    /// Wraps an OpenCL failure during `doing` into a one-line error, naming running out of
    /// device memory as such.
    pub(crate) fn error(&self, doing: &str, e: ocl::Error) -> Error {
        device_error(&self.info, doing, e)
    }
}

pub(crate) fn device_error(info: &DeviceInfo, doing: &str, e: ocl::Error) -> Error {
    use ocl::core::Status;
    let status = e.api_status();
    let what = match status {
        Some(Status::CL_MEM_OBJECT_ALLOCATION_FAILURE)
        | Some(Status::CL_OUT_OF_RESOURCES)
        | Some(Status::CL_OUT_OF_HOST_MEMORY)
        | Some(Status::CL_INVALID_BUFFER_SIZE) => format!(
            "device out of memory ({status:?}) while {doing} on {} (global memory {} MiB, largest allocation {} MiB)",
            info.name,
            info.global_memory >> 20,
            info.max_allocation >> 20
        ),
        Some(s) => format!("OpenCL error {s:?} while {doing} on {}", info.name),
        None => format!(
            "OpenCL error while {doing} on {}: {}",
            info.name,
            first_line(&e.to_string())
        ),
    };
    Error::Device(what)
}

fn first_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("")
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selectors_parse() {
        assert_eq!(
            "1:0".parse::<DeviceSelector>().unwrap(),
            DeviceSelector::Index(1, 0)
        );
        assert_eq!(
            "GPU".parse::<DeviceSelector>().unwrap(),
            DeviceSelector::Kind(DeviceKind::Gpu)
        );
        assert_eq!(
            "cpu".parse::<DeviceSelector>().unwrap(),
            DeviceSelector::Kind(DeviceKind::Cpu)
        );
        assert_eq!(
            "H100".parse::<DeviceSelector>().unwrap(),
            DeviceSelector::Name("H100".into())
        );
        assert!("".parse::<DeviceSelector>().is_err());
    }
}
