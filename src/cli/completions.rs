//! `mbsa completions SHELL` and `mbsa man [COMMAND]`: shell completion scripts and roff
//! manual pages, made from the same argument definitions as `--help`.

use super::{Cli, Failure, emit};
use clap::CommandFactory;

/// Print the completion script of `shell`.
pub fn completions(shell: clap_complete::Shell) -> Result<(), Failure> {
    let mut cmd = Cli::command();
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut cmd, "mbsa", &mut out);
    emit(&String::from_utf8_lossy(&out))
}

/// Print the manual page of mbsa, or of one of its commands (`mbsa-check(1)`).
pub fn man(command: Option<&str>) -> Result<(), Failure> {
    let mut cmd = Cli::command();
    // Built: subcommands get their display names (`mbsa-check`) and the global flags.
    cmd.build();
    let page = match command {
        None => cmd,
        Some(name) => match cmd.find_subcommand(name) {
            Some(sub) => sub.clone(),
            None => {
                let names: Vec<&str> = cmd.get_subcommands().map(|c| c.get_name()).collect();
                return Err(Failure::Input(format!(
                    "error: no command named `{name}`\n  help: the commands: {}",
                    names.join(", ")
                )));
            }
        },
    };
    let mut out = Vec::new();
    clap_mangen::Man::new(page)
        .source(format!("mbsa {}", env!("MBSA_VERSION")))
        .manual("mbsa manual")
        .render(&mut out)
        .map_err(|e| Failure::Input(format!("error: cannot render the manual page: {e}")))?;
    emit(&String::from_utf8_lossy(&out))
}
