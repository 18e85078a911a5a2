//! C-side helpers: strings, fixed-size name arrays and the two-call idiom.

use openxr::sys as xr;
use std::ffi::c_char;

use std::ffi::CStr;

pub(crate) unsafe fn cstr<'a>(p: *const c_char) -> &'a str {
    if p.is_null() {
        ""
    } else {
        // SAFETY: `p` is not null, and callers pass NUL-terminated strings from the application.
        unsafe { CStr::from_ptr(p) }.to_str().unwrap_or("")
    }
}

pub(crate) fn fixed(out: &mut [c_char], text: &str) {
    for (o, b) in out.iter_mut().zip(text.bytes().chain(std::iter::once(0))) {
        *o = b as c_char;
    }
}

/// The two-call idiom: writes `items` if there is room, always the count.
pub(crate) unsafe fn fill<T: Copy>(
    cap: u32,
    count: *mut u32,
    out: *mut T,
    items: &[T],
) -> xr::Result {
    // SAFETY: the caller guarantees that `count` is valid for writing.
    unsafe { *count = items.len() as u32 };
    if cap == 0 {
        return xr::Result::SUCCESS;
    }
    if (cap as usize) < items.len() {
        return xr::Result::ERROR_SIZE_INSUFFICIENT;
    }
    for (i, item) in items.iter().enumerate() {
        // SAFETY: `i < items.len() <= cap`, and `out` holds `cap` elements (the caller's contract).
        unsafe { *out.add(i) = *item };
    }
    xr::Result::SUCCESS
}
