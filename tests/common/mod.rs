//! Helpers shared by the end-to-end tests of the command line.

use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

/// Runs the command and checks that it succeeded, showing its stderr if not.
pub fn succeeds(command: &mut Command) -> Output {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Waits for `child` at most `seconds`; past that, kills it and fails naming `what`
/// (a command that should end at once must not hang the suite when it does not).
pub fn finishes(mut child: Child, seconds: u64, what: &str) -> Output {
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("{what}: still running after {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}
