//! The last guard of import. The checks before every read mean that no
//! file should make import panic; a panic that slips past them anyway (a
//! bug, here or in a dependency) becomes a [`Fault::Panic`] of that file
//! instead of a crash of a whole batch, and prints nothing: Rust's default
//! panic hook would print the panic message and a backtrace before the
//! one-line error a user should see.
//!
//! The hook is process-wide, so it is installed once, around whatever hook
//! was there, and stays silent only on a thread that is inside [`run`];
//! panics elsewhere reach the previous hook as before. (Import runs on the
//! caller's thread: it spawns no work of its own.)

use std::cell::{Cell, RefCell};
use std::panic::{self, AssertUnwindSafe, PanicHookInfo};
use std::sync::Once;

use super::error::Fault;

thread_local! {
    /// This thread is inside [`run`].
    static GUARDED: Cell<bool> = const { Cell::new(false) };
    /// What the silent hook saw of the last guarded panic on this thread.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

static INSTALL: Once = Once::new();

/// Runs `work`, turning a panic into [`Fault::Panic`] with its message and
/// where it was raised, and printing nothing for it.
pub fn run<T>(work: impl FnOnce() -> Result<T, Fault>) -> Result<T, Fault> {
    INSTALL.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if GUARDED.with(Cell::get) {
                LAST_PANIC.with(|last| *last.borrow_mut() = Some(describe(info)));
            } else {
                previous(info);
            }
        }));
    });
    let outer = GUARDED.with(|guarded| guarded.replace(true));
    let outcome = panic::catch_unwind(AssertUnwindSafe(work));
    GUARDED.with(|guarded| guarded.set(outer));
    outcome.unwrap_or_else(|_| {
        let description = LAST_PANIC.with(|last| last.borrow_mut().take());
        // Without a description, another hook replaced ours after install.
        Err(Fault::Panic(description.unwrap_or_else(|| {
            "a panic (its message went to another hook)".into()
        })))
    })
}

/// The panic's message and the source line that raised it, for a report.
fn describe(info: &PanicHookInfo) -> String {
    let payload = info.payload();
    let message = payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("a panic without a message");
    match info.location() {
        Some(at) => format!("{message} (at {}:{})", at.file(), at.line()),
        None => message.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::Command;

    const CHILD: &str = "LMANIM_PANIC_GUARD_CHILD";

    /// Run in a child process of its own (the hook is process-wide): a
    /// guarded panic, then an unguarded one.
    #[test]
    fn guarded_panics_print_nothing_and_others_print_as_before() {
        if std::env::var_os(CHILD).is_some() {
            let fault = run::<()>(|| panic!("guarded {}", 42)).expect_err("a panic");
            println!("fault: {fault}");
            let _ = panic::catch_unwind(|| panic!("unguarded"));
            return;
        }
        let output = Command::new(std::env::current_exe().expect("test binary"))
            .args([
                "--exact",
                "import::panic_guard::tests::guarded_panics_print_nothing_and_others_print_as_before",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(CHILD, "1")
            .output()
            .expect("run the test binary");
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stdout}\n{stderr}");
        assert!(
            stdout.contains("fault: internal error while importing (please report it): guarded 42 (at src/import/panic_guard.rs:"),
            "{stdout}"
        );
        assert!(!stderr.contains("guarded 42"), "{stderr}");
        assert!(
            stderr.contains("panicked") && stderr.contains("unguarded"),
            "{stderr}"
        );
    }

    #[test]
    fn work_that_returns_is_untouched() {
        assert_eq!(run(|| Ok::<_, Fault>(7)).ok(), Some(7));
        let fault = run::<()>(|| Err(Fault::NoScene)).expect_err("its own fault");
        assert!(matches!(fault, Fault::NoScene));
    }
}
