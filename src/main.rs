//! The `cltrace` command: parses the command line ([`flags`]) and hands the request over to
//! the library's command ([`cltrace::commands`]).

mod flags;

use std::process::ExitCode;

use cltrace::commands::{Ending, bench, bvh, devices, merge, render, tune};
use cltrace::interrupt::{self, Request};
use cltrace::report::{print_data, print_message};
use flags::Command;

// Large buffers in huge pages: fewer page faults for the cores filling them (src/huge_pages.rs).
#[global_allocator]
static ALLOCATOR: cltrace::huge_pages::HugePages = cltrace::huge_pages::HugePages;

fn main() -> ExitCode {
    generic_pocl_work_groups();
    // The first Ctrl-C (or SIGTERM) asks the work to stop at its next band, sample pass or
    // measurement and keep what it has (src/interrupt.rs); a second one ends the process.
    let _ = ctrlc::set_handler(|| match interrupt::request() {
        Request::Stop => print_message(
            "interrupted: stopping at the next band or sample pass (Ctrl-C again to quit now)",
        ),
        Request::Wait => print_message("interrupted again: quitting once the file is written"),
        Request::Exit => std::process::exit(130),
    });
    // OpenCL runtimes may replace them; the library puts them back (src/interrupt.rs).
    interrupt::keep_handlers();
    let command = match flags::parse() {
        Ok(command) => command,
        Err(code) => return code,
    };
    let result = match command {
        Command::Render(args) => render::render(&args.request()),
        Command::Merge(args) => merge::merge(&args.request()),
        Command::Devices => devices::devices_table().map(|table| {
            print_data(&table);
            Ending::Complete
        }),
        Command::Bench(args) => bench::bench(&args.command()),
        Command::Tune(args) => tune::tune(&args.request()).map(|()| Ending::Complete),
        Command::Bvh(args) => bvh::bvh_report(&args.request()).map(|report| {
            print_data(&report);
            Ending::Complete
        }),
    };
    match result {
        Ok(ending) => ExitCode::from(ending.exit_code()),
        Err(e) => {
            print_message(&format!("error: {e}"));
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

/// Has PoCL run every launch through the work-group function it compiles with the program,
/// instead of compiling one more for each launch's shape at its first launch: that took 1.4
/// s of a 3.6 s first render of the dragon on 2 cores, and the generic function traced as
/// fast (docs/bench/2026-12-04-first-image.md). Other runtimes ignore the variable; one the
/// user has set wins.
fn generic_pocl_work_groups() {
    const VAR: &str = "POCL_WORK_GROUP_SPECIALIZATION";
    if std::env::var_os(VAR).is_none() {
        // SAFETY: the first thing main does, before any other thread exists (the Ctrl-C
        // handler's comes next) or anything reads the environment.
        unsafe { std::env::set_var(VAR, "0") };
    }
}
