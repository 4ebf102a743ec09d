//! The boundary: every exported function's body runs in [`call`], which catches panics, turns
//! failures into status codes and keeps the message for [`wpbgi_last_error`]; the `checked_*`
//! helpers turn raw pointers into references only after checking them.

use crate::{
    WPBGI_CANCELLED, WPBGI_FAILED, WPBGI_INTERNAL_ERROR, WPBGI_INVALID_ARGUMENT, WPBGI_OK,
};
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{self, AssertUnwindSafe};
use std::path::PathBuf;

/// Why a call failed; each maps to one status code.
#[derive(Debug)]
pub(crate) enum Failure {
    InvalidArgument(String),
    Failed(String),
    Cancelled,
}

impl From<wpbgi::Error> for Failure {
    fn from(e: wpbgi::Error) -> Failure {
        match e {
            wpbgi::Error::Cancelled => Failure::Cancelled,
            wpbgi::Error::InvalidSetting(_) | wpbgi::Error::Edit { .. } => {
                Failure::InvalidArgument(e.to_string())
            }
            e => Failure::Failed(e.to_string()),
        }
    }
}

impl From<wpbgi::cache::CacheError> for Failure {
    fn from(e: wpbgi::cache::CacheError) -> Failure {
        Failure::Failed(e.to_string())
    }
}

pub(crate) type Outcome = Result<(), Failure>;

thread_local! {
    /// The message of this thread's last call: empty when it succeeded.
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    // A message never holds NUL; if one did, it is cut there rather than lost.
    let bytes: Vec<u8> = message.bytes().take_while(|&b| b != 0).collect();
    let text = CString::new(bytes).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Run `body` as an exported function: its status code, with the message kept.
pub(crate) fn call(body: impl FnOnce() -> Outcome) -> i32 {
    set_last_error("");
    let (status, message) = match panic::catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => return WPBGI_OK,
        Ok(Err(Failure::InvalidArgument(m))) => (WPBGI_INVALID_ARGUMENT, m),
        Ok(Err(Failure::Failed(m))) => (WPBGI_FAILED, m),
        Ok(Err(Failure::Cancelled)) => (WPBGI_CANCELLED, "the bake was cancelled".to_string()),
        Err(payload) => {
            let what = wpbgi::error::panic_message(payload.as_ref());
            (
                WPBGI_INTERNAL_ERROR,
                format!("internal error in wpbgi (please report it): {what}"),
            )
        }
    };
    set_last_error(&message);
    status
}

/// The message of the last call made on this thread: one sentence, or "" if that call
/// succeeded. The string belongs to the library and stays valid until the thread's next call
/// into it; copy it to keep it. Never NULL.
#[no_mangle]
pub extern "C" fn wpbgi_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

fn invalid(message: String) -> Failure {
    Failure::InvalidArgument(message)
}

/// `p` as a shared reference, or an error naming `what` if it is NULL.
///
/// # Safety
/// A non-NULL `p` must point to a live `T`.
pub(crate) unsafe fn checked_ref<'a, T>(p: *const T, what: &str) -> Result<&'a T, Failure> {
    // SAFETY: the caller's contract; NULL is refused here.
    unsafe { p.as_ref() }.ok_or_else(|| invalid(format!("{what} is NULL")))
}

/// `p` as an exclusive reference, or an error naming `what` if it is NULL or misaligned.
///
/// # Safety
/// A non-NULL `p` must point to memory valid for a `T` that nothing else uses during the call.
pub(crate) unsafe fn checked_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Failure> {
    if !p.is_null() && !p.is_aligned() {
        return Err(invalid(format!("{what} is not aligned for its type")));
    }
    // SAFETY: the caller's contract; NULL and misalignment are refused here.
    unsafe { p.as_mut() }.ok_or_else(|| invalid(format!("{what} is NULL")))
}

/// A settings struct whose first field is its `struct_size`, checked against this ABI's size.
///
/// # Safety
/// A non-NULL `p` must point to at least `struct_size` readable bytes.
pub(crate) unsafe fn checked_settings<'a, T>(p: *const T, what: &str) -> Result<&'a T, Failure> {
    if p.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    if !p.is_aligned() {
        return Err(invalid(format!("{what} is not aligned for its type")));
    }
    // SAFETY: every settings struct starts with a u32 `struct_size`; p is non-NULL, aligned.
    let size = unsafe { p.cast::<u32>().read() } as usize;
    if size != std::mem::size_of::<T>() {
        return Err(invalid(format!(
            "{what}->struct_size is {size} where this library's is {} (initialise the struct \
             with its _init function, and check wpbgi_abi_version)",
            std::mem::size_of::<T>()
        )));
    }
    // SAFETY: the size matches, so the whole struct is there.
    Ok(unsafe { &*p })
}

/// A NUL-terminated string as UTF-8 text.
///
/// # Safety
/// A non-NULL `p` must point to a NUL-terminated string.
pub(crate) unsafe fn checked_str<'a>(p: *const c_char, what: &str) -> Result<&'a str, Failure> {
    if p.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    // SAFETY: the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| invalid(format!("{what} is not UTF-8 text")))
}

/// A NUL-terminated file name (any bytes on Unix, UTF-8 elsewhere).
///
/// # Safety
/// A non-NULL `p` must point to a NUL-terminated string.
pub(crate) unsafe fn checked_path(p: *const c_char, what: &str) -> Result<PathBuf, Failure> {
    if p.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    // SAFETY: the caller's contract.
    let bytes = unsafe { CStr::from_ptr(p) }.to_bytes();
    if bytes.is_empty() {
        return Err(invalid(format!("{what} is empty")));
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
    }
    #[cfg(not(unix))]
    {
        std::str::from_utf8(bytes)
            .map(PathBuf::from)
            .map_err(|_| invalid(format!("{what} is not UTF-8 text")))
    }
}

/// A caller's buffer of `len` elements that must hold exactly `need`.
///
/// # Safety
/// A non-NULL `p` must point to `len` writable elements that nothing else uses during the call.
pub(crate) unsafe fn checked_buffer<'a, T>(
    p: *mut T,
    len: usize,
    need: usize,
    what: &str,
) -> Result<&'a mut [T], Failure> {
    if p.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    if !p.is_aligned() {
        return Err(invalid(format!("{what} is not aligned for its type")));
    }
    if len != need {
        return Err(invalid(format!(
            "{what} holds {len} elements where {need} are needed"
        )));
    }
    // SAFETY: the caller's contract for `len` elements; NULL and misalignment refused.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// A caller's list of `len` elements, read only.
///
/// # Safety
/// A non-NULL `p` must point to `len` readable elements that nothing changes during the call.
pub(crate) unsafe fn checked_list<'a, T>(
    p: *const T,
    len: usize,
    what: &str,
) -> Result<&'a [T], Failure> {
    if p.is_null() {
        return Err(invalid(format!("{what} is NULL")));
    }
    if !p.is_aligned() {
        return Err(invalid(format!("{what} is not aligned for its type")));
    }
    // SAFETY: the caller's contract for `len` elements; NULL and misalignment refused.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message() -> String {
        // SAFETY: never NULL, valid until the next call on this thread.
        unsafe { CStr::from_ptr(wpbgi_last_error()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_becomes_an_internal_error_and_the_next_call_works() {
        let status = call(|| panic!("the bug"));
        assert_eq!(status, WPBGI_INTERNAL_ERROR);
        assert_eq!(
            message(),
            "internal error in wpbgi (please report it): the bug"
        );
        let status = call(|| panic!("{} formatted", "also"));
        assert_eq!(
            message(),
            "internal error in wpbgi (please report it): also formatted"
        );
        assert_eq!(status, WPBGI_INTERNAL_ERROR);
        assert_eq!(call(|| Ok(())), WPBGI_OK);
        assert_eq!(message(), "");
    }

    #[test]
    fn failures_map_to_their_codes() {
        let cases = [
            (
                Failure::InvalidArgument("a".into()),
                WPBGI_INVALID_ARGUMENT,
                "a",
            ),
            (Failure::Failed("b".into()), WPBGI_FAILED, "b"),
            (
                Failure::Cancelled,
                WPBGI_CANCELLED,
                "the bake was cancelled",
            ),
            (Failure::Failed("cut\0here".into()), WPBGI_FAILED, "cut"),
        ];
        for (failure, code, text) in cases {
            assert_eq!(call(|| Err(failure)), code);
            assert_eq!(message(), text);
        }
    }

    #[test]
    fn the_message_is_per_thread() {
        call(|| Err(Failure::Failed("here".into())));
        let other = std::thread::spawn(message).join().expect("thread");
        assert_eq!(other, "");
        assert_eq!(message(), "here");
    }
}
