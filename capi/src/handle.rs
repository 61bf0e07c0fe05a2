//! What every entry point shares: the status codes, the thread-local last error, the
//! guard that turns a panic into [`StrataStatus::Panic`], the registry of live handles
//! (so that a freed or mistyped handle is refused instead of used), and the checked
//! conversions of caller pointers into slices and strings.
//!
//! Cost: an entry point pays one uncontended mutex and one hash look-up per handle it
//! takes (tens of nanoseconds), and nothing else allocates on success.

// The C ABI's raw pointers become references and slices here, and only here: each
// block says which part of the C contract makes it hold.
#![allow(unsafe_code)]

use std::cell::RefCell;
use std::collections::HashMap;
use std::ffi::{CStr, c_char};
use std::fmt::Display;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Mutex, OnceLock};

/// The result of every `strata_` function that can fail. On anything but
/// `STRATA_STATUS_OK`, `strata_last_error` holds a one-line message with the cause.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrataStatus {
    /// Success.
    Ok = 0,
    /// A required pointer was null.
    NullPointer = 1,
    /// An argument out of range: a zero or mismatched size, an unknown mode, a
    /// `struct_size` this library does not know, a string that is not UTF-8.
    InvalidArgument = 2,
    /// A handle that is not live (freed already, or never made by this library), or
    /// of another kind than the function takes.
    InvalidHandle = 3,
    /// The mesh could not be read or built (the engine's message says why).
    Mesh = 4,
    /// The field could not be built.
    Field = 5,
    /// Preprocessing failed.
    Build = 6,
    /// The build was cancelled.
    Cancelled = 7,
    /// The build has not finished: poll again later.
    NotReady = 8,
    /// A scene file or a RON text could not be read.
    Config = 9,
    /// A level-of-detail view or pool was refused.
    Lod = 10,
    /// A panic inside the library was caught (a bug in strata; the message says where).
    Panic = 11,
}

thread_local! {
    /// The last error of this thread, NUL-terminated.
    static LAST_ERROR: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// An error on its way to the caller: its status and message.
#[derive(Debug)]
pub struct Failure {
    /// The status returned.
    pub status: StrataStatus,
    /// The message kept for `strata_last_error`.
    pub message: String,
}

impl Failure {
    /// A failure with `status` and `message`.
    pub fn new(status: StrataStatus, message: impl Display) -> Self {
        Self {
            status,
            message: message.to_string(),
        }
    }
}

/// A result of an entry point's body.
pub type Outcome<T = ()> = Result<T, Failure>;

/// Stores `message` as this thread's last error.
fn set_last_error(message: &str) {
    LAST_ERROR.with(|slot| {
        let mut slot = slot.borrow_mut();
        slot.clear();
        // A NUL inside the text would end the C string early: spaces instead.
        slot.extend(message.bytes().map(|b| if b == 0 { b' ' } else { b }));
        slot.push(0);
    });
}

/// This thread's last error as a NUL-terminated string, valid until the thread's next
/// failing call; an empty string when none failed yet.
pub fn last_error_ptr() -> *const c_char {
    LAST_ERROR.with(|slot| {
        let mut slot = slot.borrow_mut();
        if slot.is_empty() {
            slot.push(0);
        }
        slot.as_ptr().cast()
    })
}

/// Runs an entry point's body: its result as a status, its error kept as the last
/// error, a panic caught and reported as [`StrataStatus::Panic`].
pub fn guard(body: impl FnOnce() -> Outcome) -> StrataStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => StrataStatus::Ok,
        Ok(Err(failure)) => {
            set_last_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown payload".to_owned());
            set_last_error(&format!("internal error (panic caught): {what}"));
            StrataStatus::Panic
        }
    }
}

/// Runs a body that returns a value with no failure path (a getter): its panic, if
/// any, becomes `fallback`.
pub fn guard_value<T>(fallback: T, body: impl FnOnce() -> T) -> T {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or(fallback)
}

/// The kinds of handle, so that one kind passed for another is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `StrataMesh`.
    Mesh,
    /// `StrataField`.
    Field,
    /// `StrataSampler`.
    Sampler,
    /// `StrataBuild`.
    Build,
    /// `StrataLod`.
    Lod,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Mesh => "mesh",
            Kind::Field => "field",
            Kind::Sampler => "sampler",
            Kind::Build => "build",
            Kind::Lod => "level-of-detail pool",
        }
    }
}

/// A type behind a handle: its kind.
pub trait Handle: Send + Sync + 'static {
    /// The kind of this handle.
    const KIND: Kind;
}

/// The live handles: address -> kind.
fn live() -> &'static Mutex<HashMap<usize, Kind>> {
    static LIVE: OnceLock<Mutex<HashMap<usize, Kind>>> = OnceLock::new();
    LIVE.get_or_init(|| Mutex::new(HashMap::new()))
}

fn lookup(address: usize) -> Option<Kind> {
    let live = live().lock().unwrap_or_else(|e| e.into_inner());
    live.get(&address).copied()
}

/// Moves `value` to the heap and registers it: the handle given to the caller.
pub fn register<T: Handle>(value: T) -> *mut T {
    let ptr = Box::into_raw(Box::new(value));
    let mut live = live().lock().unwrap_or_else(|e| e.into_inner());
    live.insert(ptr as usize, T::KIND);
    ptr
}

/// Checks that `ptr` is a live handle of kind `T`.
fn check<T: Handle>(ptr: *const T, what: &str) -> Outcome {
    if ptr.is_null() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null"),
        ));
    }
    match lookup(ptr as usize) {
        Some(kind) if kind == T::KIND => Ok(()),
        Some(kind) => Err(Failure::new(
            StrataStatus::InvalidHandle,
            format!(
                "{what} is a {} handle, not a {}",
                kind.name(),
                T::KIND.name()
            ),
        )),
        None => Err(Failure::new(
            StrataStatus::InvalidHandle,
            format!(
                "{what} is not a live {} handle (freed already, or not made by strata)",
                T::KIND.name()
            ),
        )),
    }
}

/// The value behind the live handle `ptr`.
pub fn borrow<'a, T: Handle>(ptr: *const T, what: &str) -> Outcome<&'a T> {
    check(ptr, what)?;
    // SAFETY: `ptr` is registered as a live `T`: it came from `Box::into_raw` in
    // `register` and `release` has not taken it back. Handles are only shared (`&T`;
    // their mutable state is behind locks), and the C contract (documented per handle)
    // is that a handle is not freed while another call uses it.
    Ok(unsafe { &*ptr })
}

/// Unregisters and drops the handle `ptr`; a null one is a no-op, a freed one an
/// [`StrataStatus::InvalidHandle`] error (a double free, detected while the address
/// has not been reused by a new handle).
pub fn release<T: Handle>(ptr: *mut T, what: &str) -> Outcome {
    if ptr.is_null() {
        return Ok(());
    }
    {
        let mut live = live().lock().unwrap_or_else(|e| e.into_inner());
        match live.get(&(ptr as usize)) {
            Some(kind) if *kind == T::KIND => {
                live.remove(&(ptr as usize));
            }
            _ => {
                drop(live);
                return check(ptr.cast_const(), what);
            }
        }
    }
    // SAFETY: `ptr` was registered as a live `T` made by `Box::into_raw`, and it was
    // unregistered just above under the lock, so no other `release` can take it too.
    drop(unsafe { Box::from_raw(ptr) });
    Ok(())
}

/// Writes `value` into the caller's out-parameter `out`.
pub fn write_out<T>(out: *mut T, value: T, what: &str) -> Outcome {
    if out.is_null() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null"),
        ));
    }
    // SAFETY: `out` is non-null and, by the C contract, points to writable memory for
    // one `T` (an out-parameter of the documented type). `write` does not read or drop
    // the old contents, which may be uninitialized.
    unsafe { out.write(value) };
    Ok(())
}

/// Checks an out-parameter before work whose result it will receive.
pub fn require_out<T>(out: *mut T, what: &str) -> Outcome {
    if out.is_null() {
        Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null"),
        ))
    } else {
        Ok(())
    }
}

/// The caller's array `ptr` of `len` elements (`len` may be 0 with any pointer).
pub fn slice<'a, T>(ptr: *const T, len: usize, what: &str) -> Outcome<&'a [T]> {
    if len == 0 {
        return Ok(&[]);
    }
    if ptr.is_null() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null but its length is {len}"),
        ));
    }
    check_layout::<T>(ptr as usize, len, what)?;
    // SAFETY: `ptr` is non-null and aligned for `T` (checked), the byte size fits in
    // `isize` (checked), and by the C contract it points to `len` initialized elements
    // that stay unchanged during the call.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// The caller's writable array `ptr` of `len` elements.
pub fn slice_mut<'a, T>(ptr: *mut T, len: usize, what: &str) -> Outcome<&'a mut [T]> {
    if len == 0 {
        return Ok(&mut []);
    }
    if ptr.is_null() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null but its length is {len}"),
        ));
    }
    check_layout::<T>(ptr as usize, len, what)?;
    // SAFETY: `ptr` is non-null and aligned for `T` (checked), the byte size fits in
    // `isize` (checked), and by the C contract it points to `len` writable elements
    // that nothing else reads or writes during the call. The element types used here
    // (integers, floats, `#[repr(C)]` records of them) are valid for any bit pattern,
    // so uninitialized caller memory is only ever overwritten.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

fn check_layout<T>(address: usize, len: usize, what: &str) -> Outcome {
    if !address.is_multiple_of(std::mem::align_of::<T>()) {
        return Err(Failure::new(
            StrataStatus::InvalidArgument,
            format!(
                "{what} is not aligned to {} bytes",
                std::mem::align_of::<T>()
            ),
        ));
    }
    let too_long = len
        .checked_mul(std::mem::size_of::<T>())
        .is_none_or(|bytes| bytes > isize::MAX as usize);
    if too_long {
        return Err(Failure::new(
            StrataStatus::InvalidArgument,
            format!("{what} has an impossible length {len}"),
        ));
    }
    Ok(())
}

/// The caller's NUL-terminated UTF-8 string `ptr`.
pub fn text<'a>(ptr: *const c_char, what: &str) -> Outcome<&'a str> {
    if ptr.is_null() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            format!("{what} is null"),
        ));
    }
    // SAFETY: `ptr` is non-null and, by the C contract, a NUL-terminated string that
    // stays unchanged during the call.
    let c = unsafe { CStr::from_ptr(ptr) };
    c.to_str().map_err(|e| {
        Failure::new(
            StrataStatus::InvalidArgument,
            format!("{what} is not UTF-8: {e}"),
        )
    })
}

/// Checks an option struct's `struct_size` against the size this library knows:
/// smaller is an older header (refused), larger a newer one (refused too: its extra
/// fields would be ignored silently).
pub fn check_struct_size(given: u32, expected: usize, what: &str) -> Outcome {
    if given as usize == expected {
        Ok(())
    } else {
        Err(Failure::new(
            StrataStatus::InvalidArgument,
            format!(
                "{what}.struct_size is {given}, this library's {what} has {expected} bytes \
                 (header and library differ: rebuild against this library's strata.h)"
            ),
        ))
    }
}

/// A failure of `status` with an engine error's text.
pub fn engine_error(status: StrataStatus, context: &str, error: impl Display) -> Failure {
    Failure::new(status, format!("{context}: {error}"))
}
