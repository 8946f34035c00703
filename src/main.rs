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

fn main() -> ExitCode {
    let result = match Cli::parse().command {
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
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
