//! The `cltrace` command: parses the command line ([`flags`]) and hands the request over to
//! the library's command ([`cltrace::commands`]).

mod flags;

use std::process::ExitCode;
use std::sync::atomic::Ordering;

use cltrace::commands::{bench, bvh, devices, render, tune};
use cltrace::report::{print_data, print_message};
use flags::Command;

fn main() -> ExitCode {
    let command = match flags::parse() {
        Ok(command) => command,
        Err(code) => return code,
    };
    // The first Ctrl-C asks a progressive render to stop and write what it has; a second
    // one ends the process at once.
    let _ = ctrlc::set_handler(|| {
        if render::STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    let result = match command {
        Command::Render(args) => render::render(&args.request()),
        Command::Devices => devices::devices_table().map(|table| print_data(&table)),
        Command::Bench(args) => bench::bench(&args.command()),
        Command::Tune(args) => tune::tune(&args.request()),
        Command::Bvh(args) => bvh::bvh_report(&args.request()).map(|report| print_data(&report)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            print_message(&format!("error: {e}"));
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
