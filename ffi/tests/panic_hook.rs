//! A panic inside the library is reported as `COAG_PANIC` with its message, and does
//! not reach the host's panic hook (so nothing is printed on the host's stderr); a
//! panic outside library calls still does.

use std::sync::atomic::{AtomicUsize, Ordering};

static HOST_HOOK_CALLS: AtomicUsize = AtomicUsize::new(0);

#[test]
fn library_panics_are_silent() {
    // the host's own hook, installed before the library's first call
    std::panic::set_hook(Box::new(|_| {
        HOST_HOOK_CALLS.fetch_add(1, Ordering::SeqCst);
    }));
    assert_eq!(
        coagula::panic_inside_a_call_for_tests(),
        coagula::COAG_PANIC
    );
    assert_eq!(
        HOST_HOOK_CALLS.load(Ordering::SeqCst),
        0,
        "the host saw the library's panic"
    );
    let mut msg = [0u8; 256];
    let mut len = 0usize;
    // SAFETY: a writable buffer of its length and a writable length.
    let rc =
        unsafe { coagula::coag_last_error_message(msg.as_mut_ptr().cast(), msg.len(), &mut len) };
    assert_eq!(rc, coagula::COAG_OK);
    let text = String::from_utf8_lossy(&msg[..len]);
    assert!(text.contains("a panic inside a library call"), "{text}");
    // a panic of the host's own code still reaches its hook
    let r = std::panic::catch_unwind(|| panic!("host panic"));
    assert!(r.is_err());
    assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 1);
}
