//! Errors while rendering.

/// Errors while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The GPU could not hand the image back (device lost, out of memory, …).
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
    /// A buffer would exceed what the adapter can bind (checked before anything is created).
    #[error(
        "{what} needs {} MiB, more than this adapter can bind ({} MiB){hint}",
        bytes.div_ceil(1 << 20),
        limit >> 20
    )]
    TooLarge {
        /// What the buffer is for.
        what: String,
        /// Bytes it needs.
        bytes: u64,
        /// The adapter's limit in bytes.
        limit: u64,
        /// What to do about it ("; at most … pixels" for an image), or empty.
        hint: String,
    },
}
