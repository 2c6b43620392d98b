//! The OpenCL C sources in `cl/`, embedded in the binary, and their compilation.

use std::ffi::CString;

use ocl::core::ClDeviceIdPtr;

use super::{ClDevice, first_line};
use crate::error::{Error, Result};

const HEADER: &str = include_str!("../../cl/cltrace.h");
const INCLUDE_LINE: &str = "#include \"cltrace.h\"";
/// Reads the kernel sources from this folder instead of the embedded copies (development).
const KERNEL_DIR_VAR: &str = "CLTRACE_KERNEL_DIR";
/// Extra OpenCL build options, appended to cltrace's own (development, e.g. vendor flags).
const BUILD_OPTIONS_VAR: &str = "CLTRACE_BUILD_OPTIONS";
/// When set, every successful build's log goes to stderr too (development: with
/// `-cl-nv-verbose` NVIDIA's log gives each kernel's registers and spills).
const BUILD_LOG_VAR: &str = "CLTRACE_BUILD_LOG";

/// A kernel file of `cl/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelSource {
    /// `trace.cl`: the closest-hit kernels, against the BVH when built with `STACK_SIZE`
    /// (its depth), else against every triangle.
    Trace,
    /// `sample.cl`: the progressive shade modes (ambient occlusion, shadows, path
    /// tracing), against the BVH or every triangle like `Trace`.
    Sample,
    /// `probe.cl`: reports the shared structs' layout.
    Probe,
}

impl KernelSource {
    pub fn file_name(self) -> &'static str {
        match self {
            KernelSource::Trace => "trace.cl",
            KernelSource::Sample => "sample.cl",
            KernelSource::Probe => "probe.cl",
        }
    }

    fn text(self) -> &'static str {
        match self {
            KernelSource::Trace => include_str!("../../cl/trace.cl"),
            KernelSource::Sample => include_str!("../../cl/sample.cl"),
            KernelSource::Probe => include_str!("../../cl/probe.cl"),
        }
    }

    /// The complete source: the kernel file with the shared header spliced in where it
    /// includes it (the program is built from memory, where `#include` finds no files).
    /// With `CLTRACE_KERNEL_DIR` set, the files are read from that folder instead of the
    /// copies embedded in the binary: for trying kernel changes without rebuilding.
    pub fn source(self) -> String {
        match std::env::var_os(KERNEL_DIR_VAR) {
            Some(dir) => {
                let dir = std::path::Path::new(&dir);
                let read = |name: &str| {
                    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| {
                        // An unreadable override must not silently fall back.
                        format!("#error \"{KERNEL_DIR_VAR}: cannot read {name}: {e}\"\n")
                    })
                };
                read(self.file_name()).replacen(INCLUDE_LINE, &read("cltrace.h"), 1)
            }
            None => self.text().replacen(INCLUDE_LINE, HEADER, 1),
        }
    }
}

impl ClDevice {
    /// Compiles `kernel` for this device with `-D name=value` for each define. The host
    /// and device must round identically, so division and square root are correctly
    /// rounded where the device offers it. A failed build reports the device's build log.
    pub fn build(&self, kernel: KernelSource, defines: &[(&str, String)]) -> Result<ocl::Program> {
        self.build_all(&[kernel], defines)
    }

    /// Compiles several kernel files into one program (the shared header's include guard
    /// keeps its second copy out).
    pub fn build_all(
        &self,
        kernels: &[KernelSource],
        defines: &[(&str, String)],
    ) -> Result<ocl::Program> {
        let mut options = String::from("-cl-std=CL1.2");
        if self.info.correctly_rounded_divide {
            options.push_str(" -cl-fp32-correctly-rounded-divide-sqrt");
        }
        for (name, value) in defines {
            options.push_str(&format!(" -D {name}={value}"));
        }
        if let Ok(extra) = std::env::var(BUILD_OPTIONS_VAR) {
            options.push(' ');
            options.push_str(&extra);
        }
        let names: Vec<&str> = kernels.iter().map(|k| k.file_name()).collect();
        let source: String = kernels
            .iter()
            .map(|k| k.source())
            .collect::<Vec<_>>()
            .join("\n");
        self.build_source(&names.join(" + "), &source, &options)
    }

    /// Compiles arbitrary source; `name` labels errors.
    pub fn build_source(&self, name: &str, source: &str, options: &str) -> Result<ocl::Program> {
        let fail = |e: ocl::core::Error| {
            Error::Device(format!(
                "cannot compile {name} for {}: {}",
                self.info.name,
                first_line(&e.to_string())
            ))
        };
        let source = CString::new(source)
            .map_err(|_| Error::Device(format!("{name} contains a NUL byte")))?;
        let options = CString::new(options).expect("build options contain no NUL");
        let program =
            ocl::core::create_program_with_source(&self.context, &[source]).map_err(fail)?;
        let status = unsafe {
            ocl::core::ffi::clBuildProgram(
                program.as_ptr(),
                1,
                &self.info.device.as_core().as_ptr(),
                options.as_ptr(),
                None,
                std::ptr::null_mut(),
            )
        };
        let log = || match ocl::core::get_program_build_info(
            &program,
            self.info.device.as_core(),
            ocl::core::ProgramBuildInfo::BuildLog,
        ) {
            Ok(log) => log.to_string(),
            Err(e) => format!("(no build log: {e})"),
        };
        if status != 0 {
            let log = log();
            return Err(Error::Device(format!(
                "kernel {name} failed to build on {} (OpenCL status {status}); build log:\n{}",
                self.info.name,
                log.trim_end()
            )));
        }
        if std::env::var_os(BUILD_LOG_VAR).is_some() {
            eprintln!("build log of {name} ({options:?}):\n{}", log().trim_end());
        }
        Ok(ocl::Program::from(program))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_spliced_into_every_kernel() {
        for k in [
            KernelSource::Trace,
            KernelSource::Sample,
            KernelSource::Probe,
        ] {
            let s = k.source();
            assert!(s.contains("typedef struct"), "{}", k.file_name());
            assert!(!s.contains(INCLUDE_LINE), "{}", k.file_name());
        }
    }
}
