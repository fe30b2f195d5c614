//! Plain data and the arrays that hold it: owned, or borrowed from a read-only mapping of a
//! scene image ([`crate::scene::image`]) so that every process on a node shares one copy
//! through the page cache.
//!
//! A [`Plain`] type is `Copy`, has no padding, no pointers, and every bit pattern is a valid
//! value of it, so that its bytes can be written to a file and a slice of it viewed in a
//! mapping (after the mapping's size, alignment and checksum are checked). Values read from a
//! mapping are still checked where a wrong one could index out of bounds (indices are
//! validated when a scene image is loaded).

use std::ops::Deref;
use std::sync::Arc;

use glam::{DVec3, Vec3};

/// Plain data (see the module's documentation).
///
/// # Safety
/// Implementors must be `#[repr(C)]` (or a primitive) without padding bytes, hold no
/// pointers or references, and accept every bit pattern as a valid value.
pub unsafe trait Plain: Copy + Send + Sync + 'static {}

// SAFETY: primitives without invalid bit patterns.
unsafe impl Plain for u8 {}
// SAFETY: as above.
unsafe impl Plain for i8 {}
// SAFETY: as above.
unsafe impl Plain for u16 {}
// SAFETY: as above.
unsafe impl Plain for i16 {}
// SAFETY: as above.
unsafe impl Plain for u32 {}
// SAFETY: as above.
unsafe impl Plain for u64 {}
// SAFETY: as above.
unsafe impl Plain for f32 {}
// SAFETY: as above.
unsafe impl Plain for f64 {}
// SAFETY: an array of plain values has no padding between its elements.
unsafe impl<T: Plain, const N: usize> Plain for [T; N] {}
// SAFETY: glam's DVec3 is `#[repr(C)]` { x, y, z: f64 } (24 bytes, no padding).
unsafe impl Plain for DVec3 {}
// SAFETY: glam's Vec3 is `#[repr(C)]` { x, y, z: f32 } (12 bytes, no padding).
unsafe impl Plain for Vec3 {}
// SAFETY: obvhs's CwBvhNode is `#[repr(C)]`, 80 bytes, bytemuck `Pod` (no padding, any bits).
unsafe impl Plain for obvhs::cwbvh::node::CwBvhNode {}

const _: () = assert!(std::mem::size_of::<DVec3>() == 24 && std::mem::size_of::<Vec3>() == 12);
const _: () = assert!(std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>() == 80);

/// The bytes of a slice of plain values.
pub fn bytes_of<T: Plain>(s: &[T]) -> &[u8] {
    // SAFETY: `T: Plain` has no padding, so every byte of the slice is initialised.
    unsafe { std::slice::from_raw_parts(s.as_ptr().cast::<u8>(), std::mem::size_of_val(s)) }
}

/// Something that holds read-only bytes alive (a mapping, or an aligned buffer in tests).
pub trait Backing: Send + Sync + 'static {
    /// The bytes.
    fn bytes(&self) -> &[u8];
}

impl Backing for memmap2::Mmap {
    fn bytes(&self) -> &[u8] {
        self
    }
}

/// A buffer of bytes aligned to 16, for images built in memory.
pub struct Aligned(Vec<u128>, usize);

impl Aligned {
    /// A copy of `b` at an address aligned to 16.
    pub fn new(b: &[u8]) -> Aligned {
        let mut v = vec![0u128; b.len().div_ceil(16)];
        // SAFETY: `v` has at least `b.len()` bytes; u128 has no invalid bit patterns.
        unsafe {
            std::ptr::copy_nonoverlapping(b.as_ptr(), v.as_mut_ptr().cast::<u8>(), b.len());
        }
        Aligned(v, b.len())
    }
}

impl Backing for Aligned {
    fn bytes(&self) -> &[u8] {
        // SAFETY: the first `self.1` bytes of the buffer are initialised (copied in `new`).
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast::<u8>(), self.1) }
    }
}

/// An array of plain values: owned, or a view into shared read-only bytes. Reading it is
/// one pointer and one length, whichever it is (no branch on the hot path of tracing).
pub struct Slab<T: Plain> {
    /// The values: into `owner`'s vector or into the shared bytes.
    ptr: *const T,
    len: usize,
    owner: Owner<T>,
}

enum Owner<T> {
    /// Owned values (`ptr` and `len` are refreshed after every change).
    Owned(Vec<T>),
    /// Keeps the shared bytes alive.
    Shared(Arc<dyn Backing>),
}

// SAFETY: a slab only reads values it owns or immutable bytes that its `Arc` (Send + Sync)
// keeps alive; changing it takes `&mut self`.
unsafe impl<T: Plain> Send for Slab<T> {}
// SAFETY: as above.
unsafe impl<T: Plain> Sync for Slab<T> {}

impl<T: Plain> Slab<T> {
    /// An empty owned slab.
    pub fn new() -> Slab<T> {
        Slab::from(Vec::new())
    }

    /// A view of `len` values at byte `offset` of `keep`'s bytes. Errors when the range is
    /// outside the bytes or the offset is not aligned for `T`.
    pub fn shared(keep: &Arc<dyn Backing>, offset: usize, len: usize) -> Result<Slab<T>, String> {
        let bytes = keep.bytes();
        let size = len
            .checked_mul(std::mem::size_of::<T>())
            .ok_or("array size overflows")?;
        let end = offset.checked_add(size).ok_or("array size overflows")?;
        if end > bytes.len() {
            return Err(format!(
                "array of {len} at byte {offset} runs past the end ({} bytes)",
                bytes.len()
            ));
        }
        // SAFETY: `offset <= bytes.len()` (checked above), so the pointer is in bounds.
        let ptr = unsafe { bytes.as_ptr().add(offset) };
        if !(ptr as usize).is_multiple_of(std::mem::align_of::<T>()) {
            return Err(format!("array at byte {offset} is not aligned"));
        }
        Ok(Slab {
            ptr: ptr.cast::<T>(),
            len,
            owner: Owner::Shared(keep.clone()),
        })
    }

    /// Whether the values are borrowed from shared bytes.
    pub fn is_shared(&self) -> bool {
        matches!(self.owner, Owner::Shared(_))
    }

    /// Change the values as a vector (a shared slab is copied first).
    pub fn with_vec<R>(&mut self, f: impl FnOnce(&mut Vec<T>) -> R) -> R {
        if let Owner::Shared(_) = self.owner {
            self.owner = Owner::Owned(self.deref().to_vec());
        }
        let Owner::Owned(v) = &mut self.owner else {
            unreachable!("made owned above")
        };
        let r = f(v);
        self.ptr = v.as_ptr();
        self.len = v.len();
        r
    }

    /// Add a value (a shared slab is copied first).
    pub fn push(&mut self, v: T) {
        self.with_vec(|s| s.push(v));
    }
}

impl<T: Plain> Default for Slab<T> {
    fn default() -> Self {
        Slab::new()
    }
}

impl<T: Plain> Deref for Slab<T> {
    type Target = [T];

    #[inline(always)]
    fn deref(&self) -> &[T] {
        // SAFETY: `ptr` and `len` describe the owned vector (refreshed after every change,
        // and a vector's buffer does not move when the slab does) or values in the shared
        // bytes `owner` keeps alive (checked in `shared`); `T: Plain` accepts any bits.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl<T: Plain> From<Vec<T>> for Slab<T> {
    fn from(v: Vec<T>) -> Self {
        Slab {
            ptr: v.as_ptr(),
            len: v.len(),
            owner: Owner::Owned(v),
        }
    }
}

impl<T: Plain> Clone for Slab<T> {
    fn clone(&self) -> Self {
        match &self.owner {
            Owner::Owned(v) => Slab::from(v.clone()),
            Owner::Shared(keep) => Slab {
                ptr: self.ptr,
                len: self.len,
                owner: Owner::Shared(keep.clone()),
            },
        }
    }
}

impl<T: Plain + std::fmt::Debug> std::fmt::Debug for Slab<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Slab[{}{}]",
            self.len(),
            if self.is_shared() { ", shared" } else { "" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_views_check_bounds_and_alignment() {
        let vals = [1.5f64, -2.0, 3.25];
        let mut b = vec![0u8; 8];
        b.extend_from_slice(bytes_of(&vals));
        let keep: Arc<dyn Backing> = Arc::new(Aligned::new(&b));
        let s = Slab::<f64>::shared(&keep, 8, 3).unwrap();
        assert_eq!(&*s, &vals);
        assert!(s.is_shared());
        assert!(Slab::<f64>::shared(&keep, 8, 4).is_err());
        assert!(Slab::<f64>::shared(&keep, 4, 1).is_err());
        assert!(Slab::<f64>::shared(&keep, usize::MAX, 2).is_err());
        let mut c = s.clone();
        c.push(7.0);
        let moved = [c];
        let c = &moved[0];
        assert!(!c.is_shared());
        assert_eq!(&c[..], &[1.5, -2.0, 3.25, 7.0]);
        assert_eq!(&*s, &vals);
    }
}
