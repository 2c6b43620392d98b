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
