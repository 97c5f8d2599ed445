//! What the command-line tests share: running the `pendkit` binary this package builds.

use std::process::Command;

/// Runs `pendkit args...` and returns (exit status 0, stdout, stderr).
pub fn pendkit(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .args(args)
        .output()
        .expect("pendkit runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// [`pendkit`] with the environment variables `env` set for the run (the limits'
/// `PENDKIT_MAX_...`, which a process reads once).
pub fn pendkit_env(args: &[&str], env: &[(&str, &str)]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("pendkit runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
