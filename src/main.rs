//! The `caustics` command line: render, reference, bench, demo, info
//! (arguments and shared checks in `cli/`, one file per command).

mod cli;

// Counts the Rust heap in use, for `bench --memory-samples` (vk/host_memory.rs).
#[global_allocator]
static HEAP: caustics::vk::CountingAllocator = caustics::vk::CountingAllocator;

use caustics::params::Params;
use caustics::techniques;
use clap::Parser;
use cli::{check_size, Cli, Command, DemoArgs, SceneArgs};
use std::process::ExitCode;

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so printing into a closed pipe (`| head`)
    // panicked; with the default action the process ends quietly, as Unix
    // tools do. Outputs are written under temporary names and renamed, so
    // this cannot leave a partial file at an output name.
    // SAFETY: called first, before any other thread exists.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    match cli::interrupt::install().and_then(|()| run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", caustics::scene::escape_control(&describe(&e)));
            ExitCode::FAILURE
        }
    }
}

/// A command line clap refuses: `--help` and `--version` print as clap
/// prints them (exit 0); a bad one is one line naming the argument (clap's
/// first line and its tip, without the usage block), exit code 1 like
/// every other bad input.
fn usage_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => e.exit(),
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            return ExitCode::FAILURE;
        }
        _ => {}
    }
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut line = lines.next().unwrap_or("error: bad command line").to_owned();
    if let Some(tip) = lines.find(|l| l.starts_with("tip:")) {
        line.push_str(&format!(" ({tip})"));
    }
    eprintln!("{line}; see --help");
    ExitCode::FAILURE
}

/// The error and its causes on one line, like `{e:#}`, but without repeating a
/// cause that a message already quotes (`SceneError::Read` and `VkError`
/// variants put their source in their own message and also report it as the
/// source, which `{e:#}` printed twice).
fn describe(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if line.is_empty() {
            line = m;
        } else if !line.contains(&m) {
            line.push_str(": ");
            line.push_str(&m);
        }
    }
    line
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(DemoArgs {
            scene,
            technique,
            params,
            width,
            height,
            present_mode,
            frames,
            exit,
            resize_test,
            compare_test,
            frames_in_flight,
            device,
        }) => {
            let technique = if technique == "auto" {
                let picked = techniques::auto(&cli::load_scene(&scene, 0.0)?);
                println!("technique: {picked} (auto)");
                picked.to_owned()
            } else {
                technique
            };
            let info = techniques::find(&technique)?;
            let params = Params::resolve(&technique, info.params(), &params)?;
            check_size(&SceneArgs {
                file: scene.clone(),
                width,
                height,
                time: 0.0,
            })?;
            cli::FrameArgs {
                frames_in_flight,
                pass_timing: false,
            }
            .options()?;
            if frames == Some(0) {
                anyhow::bail!("--frames must be at least 1");
            }
            if compare_test == Some(0) {
                anyhow::bail!("--compare-test must be at least 1");
            }
            caustics::app::run(caustics::app::DemoOptions {
                allowed: scene.allowed()?,
                scene: scene.scene,
                technique,
                params,
                width,
                height,
                present_mode: caustics::app::parse_present_mode(&present_mode)?,
                frames,
                exit,
                resize_test,
                frames_in_flight,
                validate: device.validate,
                validate_sync: device.validate_sync,
                device: device.device,
                compare_test,
            })
        }
        Command::Info => cli::info::info(),
        Command::Render(args) => cli::render::render(args),
        Command::Reference(args) => cli::reference::reference(args),
        Command::Bench(args) => cli::render::bench(args),
        Command::Compare(args) => cli::compare::compare(args),
    }
}
