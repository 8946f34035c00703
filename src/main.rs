//! The `kinsynth` command line: a thin shell over the library. This file parses the command
//! line and dispatches; each command lives in its own file under `cli/`.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Task-based kinematic design of serial manipulators in cluttered environments.
#[derive(Parser)]
#[command(name = "kinsynth", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Scenario(cli::scenario::Args),
    Check(cli::check::Args),
    Optimize(cli::optimize::Args),
    Experiment(cli::experiment::Args),
    Merge(cli::merge::Args),
    Reach(cli::reach::Args),
    Urdf(cli::urdf::Args),
    Edges(cli::edges::Args),
    View(cli::view::Args),
}

/// A command-line error of the parser as one line: its message and the values or arguments it
/// names, without the usage block and hints (which `--help` gives).
fn one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let mut parts = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Usage:") {
            break;
        }
        if line.is_empty() || line.starts_with("tip:") || line.starts_with("For more information") {
            continue;
        }
        parts.push(line);
    }
    parts.join(" ")
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            eprintln!("{}", one_line(&e));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Scenario(a) => cli::scenario::run(a),
        Command::Check(a) => cli::check::run(a),
        Command::Optimize(a) => cli::optimize::run(a),
        Command::Experiment(a) => cli::experiment::run(a),
        Command::Merge(a) => cli::merge::run(a),
        Command::Reach(a) => cli::reach::run(a),
        Command::Urdf(a) => cli::urdf::run(a),
        Command::Edges(a) => cli::edges::run(a),
        Command::View(a) => cli::view::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", kinsynth::error::shorten(&e.to_string()));
            ExitCode::FAILURE
        }
    }
}
