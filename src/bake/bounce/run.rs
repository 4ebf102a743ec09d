//! A run of plain values (one of a receiver's link arrays), owned or read in place from bytes
//! that stay put while it lives: a kept transport's file, mapped into memory. Its links are
//! hundreds of MB (cbox-glossy: 730), and copying them out of the map was most of reading it,
//! every fresh page the copies filled cleared by the kernel first (`clear_page` under
//! `memmove`: a tenth of a cbox-glossy relight's perf samples); read in place, cbox-glossy's
//! transport read went from 0.27 to 0.10 s.

use std::ops::{Deref, Range};
use std::sync::Arc;

/// Bytes that runs may borrow: a mapped file, or a buffer.
pub type SharedBytes = Arc<dyn AsRef<[u8]> + Send + Sync>;

/// Values of type `T`, owned or in place.
pub enum Run<T> {
    /// Values of their own.
    Owned(Box<[T]>),
    /// The values `range` of `bytes` holds, checked when made ([`Run::in_place`]) to be whole
    /// `T`s at `T`'s alignment.
    InPlace {
        /// What holds them.
        bytes: SharedBytes,
        /// Where, in bytes.
        range: Range<usize>,
    },
}

impl<T: bytemuck::Pod> Run<T> {
    /// The values in bytes `range` of `bytes`, in place, where they are whole `T`s aligned for
    /// `T` in the machine's byte order (the caller's to know); `None` where they are not.
    pub fn in_place(bytes: &SharedBytes, range: Range<usize>) -> Option<Run<T>> {
        let held = (**bytes).as_ref().get(range.clone())?;
        bytemuck::try_cast_slice::<u8, T>(held).ok()?;
        Some(Run::InPlace {
            bytes: bytes.clone(),
            range,
        })
    }

    /// The values, to change: copied out first where they are in place.
    pub fn to_mut(&mut self) -> &mut [T] {
        if let Run::InPlace { .. } = self {
            *self = Run::Owned(self.to_vec().into_boxed_slice());
        }
        match self {
            Run::Owned(values) => values,
            Run::InPlace { .. } => unreachable!("made owned above"),
        }
    }
}

impl<T: bytemuck::Pod> Deref for Run<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match self {
            Run::Owned(values) => values,
            // Checked by `in_place`: in range, aligned, whole values.
            Run::InPlace { bytes, range } => {
                bytemuck::cast_slice(&(**bytes).as_ref()[range.clone()])
            }
        }
    }
}

impl<T> Default for Run<T> {
    fn default() -> Self {
        Run::Owned(Box::default())
    }
}

impl<T> From<Vec<T>> for Run<T> {
    fn from(values: Vec<T>) -> Self {
        Run::Owned(values.into_boxed_slice())
    }
}

impl<T> From<Box<[T]>> for Run<T> {
    fn from(values: Box<[T]>) -> Self {
        Run::Owned(values)
    }
}

/// Bytes held four-aligned (in words), as a mapped file's are page-aligned: for tests of what
/// reads in place.
#[cfg(test)]
pub(crate) struct AlignedBytes {
    words: Vec<u32>,
    len: usize,
}

#[cfg(test)]
impl AlignedBytes {
    /// `bytes`, copied to a four-aligned start.
    pub(crate) fn shared(bytes: &[u8]) -> SharedBytes {
        let mut words = vec![0u32; bytes.len().div_ceil(4)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
        Arc::new(AlignedBytes {
            words,
            len: bytes.len(),
        })
    }
}

#[cfg(test)]
impl AsRef<[u8]> for AlignedBytes {
    fn as_ref(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.words)[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_in_place_read_what_they_cover_and_refuse_misaligned_bytes() {
        let bytes = AlignedBytes::shared(bytemuck::cast_slice::<u32, u8>(&[1, 2, 3, 4]));
        let mut run = Run::<u32>::in_place(&bytes, 4..12).expect("aligned");
        assert_eq!(&*run, &[2, 3]);
        run.to_mut()[0] = 7;
        assert_eq!(&*run, &[7, 3]);
        assert!(matches!(run, Run::Owned(_)), "copied out to change");
        assert!(Run::<u32>::in_place(&bytes, 2..10).is_none(), "misaligned");
        assert!(
            Run::<u32>::in_place(&bytes, 4..10).is_none(),
            "not whole values"
        );
        assert!(
            Run::<u32>::in_place(&bytes, 8..20).is_none(),
            "past the end"
        );
    }
}
