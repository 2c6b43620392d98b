//! `cltrace bench`: the benchmark matrix ([`crate::bench`]) as a Markdown table on stdout,
//! and, if asked, as CSV, JSON and (for the scaling study) a plot.

use std::path::PathBuf;

use super::Ending;
use crate::bench::{self, BenchRequest};
use crate::error::{Error, Result};
use crate::output::check_output;
use crate::report::{print_data, print_message};

/// Everything `cltrace bench` was asked to do.
#[derive(Clone, Debug)]
pub struct BenchCommand {
    /// What to measure; with `scaling`, the base of the scaling study's request.
    pub request: BenchRequest,
    /// Measure the BVH methods on generated hillsides of growing size instead of the scenes.
    pub scaling: bool,
    /// With `scaling`, the largest hillside's triangles.
    pub scaling_to: u64,
    /// Also write the rows as CSV here.
    pub csv: Option<PathBuf>,
    /// Also write the rows as JSON here.
    pub json: Option<PathBuf>,
    /// With `scaling`, also draw the scaling plot (PNG) here.
    pub plot: Option<PathBuf>,
}

/// Runs the benchmark, prints its table and writes the files asked for. Every output
/// folder is checked before anything is measured. Interrupted (Ctrl-C), the rows measured
/// so far are printed and written, and the ending is [`Ending::Partial`].
pub fn bench(cmd: &BenchCommand) -> Result<Ending> {
    for path in [&cmd.csv, &cmd.json, &cmd.plot].into_iter().flatten() {
        check_output(path)?;
    }
    let (rows, complete) = if cmd.scaling {
        let (rows, complete) = scaling(cmd)?;
        print_data(&bench::scaling_table(&rows));
        if let Some(plot) = &cmd.plot {
            bench::plot_scaling(&rows, plot)?;
        }
        (rows, complete)
    } else {
        let (rows, complete) = bench::run(&cmd.request)?;
        print_data(&bench::markdown(&rows));
        (rows, complete)
    };
    if let Some(csv) = &cmd.csv {
        bench::write_csv(&rows, csv)?;
    }
    if let Some(json) = &cmd.json {
        bench::write_json(&rows, json)?;
    }
    if complete {
        return Ok(Ending::Complete);
    }
    if cmd.request.verbosity.progress() {
        print_message(&format!(
            "interrupted: the {} runs measured are above, the rest were not run",
            rows.len()
        ));
    }
    Ok(Ending::Partial)
}

/// The scaling study, size by size. A size that cannot be made or measured (host or
/// device memory) ends the study with a note naming the largest that could, unless it is
/// the first.
fn scaling(cmd: &BenchCommand) -> Result<(Vec<bench::BenchRow>, bool)> {
    let mut rows = Vec::new();
    let mut largest = None;
    for size in bench::scaling_sizes(cmd.scaling_to)? {
        match bench::run(&bench::scaling_request(&cmd.request, size)) {
            Ok((more, complete)) => {
                rows.extend(more);
                largest = Some(size);
                if !complete {
                    return Ok((rows, false));
                }
            }
            Err(Error::Interrupted) if !rows.is_empty() => return Ok((rows, false)),
            Err(e) => match largest {
                Some(largest) => {
                    print_message(&format!(
                        "note: the study stops at {size} triangles ({e}); the largest measured has {largest}"
                    ));
                    break;
                }
                None => return Err(e),
            },
        }
    }
    Ok((rows, true))
}
