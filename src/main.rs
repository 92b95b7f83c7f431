//! `imudrift`: the command-line front end of the imudrift workspace.
//!
//! Thin by design: argument parsing, file I/O, progress bars and plots live here; every
//! piece of physics and statistics lives in the library crates under `crates/`.
//! (The modules are compiled as the `imudrift` library too, so the fuzz targets and the
//! property tests can reach the log reader; the library is not a public API.)

use imudrift::*;

use clap::error::ErrorKind;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "imudrift",
    version,
    about = "Monte Carlo laboratory for inertial-sensor drift"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Monte Carlo drift of a scenario (or of a sensor lying still); drift beside its analytic laws
    Simulate(cmd_simulate::Args),
    /// Write a synthetic static IMU log (CSV) from a sensor model
    Generate(cmd_generate::Args),
    /// Allan deviations of a log's channels, with confidence intervals and fitted noise terms
    Allan(cmd_allan::Args),
    /// Sensors side by side: drift with laws, requirements pass/fail, spec values read back
    Spec(cmd_spec::Args),
    /// How long a static log must be to read each noise term to a stated uncertainty
    Plan(cmd_plan::Args),
    /// Find where model and measurement disagree, name the missing effect, show the gap shrink
    Diagnose(cmd_diagnose::Args),
    /// Combine shard outputs of `simulate --shard i/k` into the single-machine result
    Merge(cmd_merge::Args),
    /// Drift measured on static logs against the model's prediction under one protocol, with a verdict per horizon and quantity and one for all of them together
    Drift(cmd_drift::Args),
    /// Print a shell completion script on stdout (e.g. `imudrift completions bash > /etc/bash_completion.d/imudrift`)
    Completions {
        /// The shell
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) on stdout, or write imudrift.1 and one page per command into DIR
    Man {
        /// Write imudrift.1 and imudrift-<command>.1 into this directory
        #[arg(long, value_name = "DIR")]
        out: Option<std::path::PathBuf>,
    },
}

/// The whole command line, every option that takes a value accepting a negative number
/// (`--rate -5`, `--latitude -33.9`): the value then reaches the option's own check, which says
/// what the option expects (`--rate: expected a sample rate in Hz > 0, found -5`), where clap
/// alone read `-5` as an unknown flag ("unexpected argument '-5' found"). Only a value that is a
/// number is taken this way; every other word starting with `-` is still a flag.
fn command() -> clap::Command {
    fn negatives(cmd: clap::Command) -> clap::Command {
        cmd.mut_args(|a| {
            if a.get_action().takes_values() {
                a.allow_negative_numbers(true)
            } else {
                a
            }
        })
        .mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

/// `imudrift completions SHELL`: clap_complete's script for the whole command line.
fn completions(shell: clap_complete::Shell) -> anyhow::Result<()> {
    let mut buf = Vec::new();
    clap_complete::generate(shell, &mut command(), "imudrift", &mut buf);
    output::print_stdout(&String::from_utf8_lossy(&buf))
}

/// `imudrift man [--out DIR]`: clap_mangen's pages, the command's and one per subcommand.
fn man(out: Option<&std::path::Path>) -> anyhow::Result<()> {
    let cmd = command();
    let render = |c: clap::Command| -> anyhow::Result<String> {
        let mut buf = Vec::new();
        clap_mangen::Man::new(c).render(&mut buf)?;
        Ok(String::from_utf8_lossy(&buf).into_owned())
    };
    let Some(dir) = out else {
        return output::print_stdout(&render(cmd)?);
    };
    let _lock = output::prepare_dir(dir)?;
    let mut pages = vec![("imudrift.1".to_string(), render(cmd.clone())?)];
    for sub in cmd.get_subcommands() {
        // clap takes a command's name as a static string (without its `string` feature): the
        // few page names live until the process ends anyway.
        let name: &'static str = Box::leak(format!("imudrift-{}", sub.get_name()).into_boxed_str());
        pages.push((format!("{name}.1"), render(sub.clone().name(name))?));
    }
    let set = output::begin_out_set(dir)?;
    for (name, text) in &pages {
        output::write_string(&dir.join(name), text)?;
    }
    set.commit()?;
    tell!("wrote {} man pages to {}", pages.len(), dir.display());
    if let Some(note) = man_path_note(dir) {
        tell!("note: {note}");
    }
    Ok(())
}

/// Where `man` will not find the pages written to `dir`, what to do instead. `man NAME` looks in
/// the `man1` directory of each root of the manual path, which `manpath` prints (man-db derives
/// it from PATH: `~/.cargo/bin` on PATH puts `~/.cargo/share/man` on it, `~/.local/bin` puts
/// `~/.local/share/man`, each only where that directory exists); None where `dir` is on it or
/// `manpath` cannot be run (nothing to say).
fn man_path_note(dir: &std::path::Path) -> Option<String> {
    let out = std::process::Command::new("manpath").output().ok()?;
    if !out.status.success() {
        return None;
    }
    let roots = String::from_utf8_lossy(&out.stdout);
    let dir = std::fs::canonicalize(dir).ok()?;
    let found = dir.file_name().is_some_and(|n| n == "man1")
        && roots.trim().split(':').any(|root| {
            std::fs::canonicalize(root).is_ok_and(|r| Some(r.as_path()) == dir.parent())
        });
    (!found).then(|| {
        format!(
            "`man imudrift-allan` does not find these pages: man reads the man1 directory under each root of `manpath` ({}), and {} is not one; read a page with `man -l {}`, or write the pages into ~/.cargo/share/man/man1, which man searches while ~/.cargo/bin is on PATH",
            roots.trim(),
            dir.display(),
            dir.join("imudrift-allan.1").display(),
        )
    })
}

fn main() -> std::process::ExitCode {
    let cli = match command()
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m))
    {
        Ok(cli) => cli,
        Err(e) => {
            // A value a flag cannot take is an error like any other (status 1, docs/cli.md);
            // help, version and usage errors (an unknown flag, a missing argument) keep clap's
            // status.
            let code = match e.kind() {
                ErrorKind::InvalidValue | ErrorKind::ValueValidation => 1,
                _ => e.exit_code(),
            };
            let _ = e.print();
            return std::process::ExitCode::from(code as u8);
        }
    };
    output::clean_up_on_signals();
    if let Err(e) = cli::check_environment() {
        tell!("error: {e:#}");
        return std::process::ExitCode::FAILURE;
    }
    let result = match cli.command {
        Command::Simulate(a) => cmd_simulate::run(a),
        Command::Generate(a) => cmd_generate::run(a),
        Command::Allan(a) => cmd_allan::run(a),
        Command::Spec(a) => cmd_spec::run(a),
        Command::Plan(a) => cmd_plan::run(a),
        Command::Diagnose(a) => cmd_diagnose::run(a),
        Command::Merge(a) => cmd_merge::run(a),
        Command::Drift(a) => cmd_drift::run(a),
        Command::Completions { shell } => completions(shell),
        Command::Man { out } => man(out.as_deref()),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            tell!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
