//! Pitched device images: 2D buffers whose rows start at multiples of the device's
//! alignment, as the thesis's `cudaMallocPitch`, read back with a rectangular read so that
//! the row padding never reaches the host.

use ocl::OclPrm;

use super::{ClDevice, device_error};
use crate::error::Result;

/// A `width` x `height` image of `T` on the device, `pitch` elements from row to row.
pub(crate) struct PitchedBuffer<T: OclPrm> {
    pub(crate) buffer: ocl::Buffer<T>,
    pub(crate) width: usize,
    pub(crate) height: usize,
    /// Elements from the start of one row to the next (a multiple of the alignment).
    pub(crate) pitch: usize,
}

impl<T: OclPrm> PitchedBuffer<T> {
    /// Row pitch in bytes for `width` elements: `width * size_of::<T>()` rounded up to
    /// the device's pitch alignment.
    pub(crate) fn pitch_bytes_for(device: &ClDevice, width: usize) -> usize {
        let align = device.info.pitch_alignment();
        (width * size_of::<T>()).div_ceil(align) * align
    }

    /// An image the kernels only write (hits, colours).
    pub(crate) fn new(device: &ClDevice, width: usize, height: usize) -> Result<Self> {
        Self::with_flags(device, width, height, ocl::flags::MEM_WRITE_ONLY)
    }

    /// An image the kernels add to, so read as well as write (the accumulation of the
    /// progressive modes): reading a write-only buffer is undefined behaviour in OpenCL,
    /// which NVIDIA and PoCL tolerate and Oclgrind reports.
    pub(crate) fn read_write(device: &ClDevice, width: usize, height: usize) -> Result<Self> {
        Self::with_flags(device, width, height, ocl::flags::MEM_READ_WRITE)
    }

    fn with_flags(
        device: &ClDevice,
        width: usize,
        height: usize,
        flags: ocl::flags::MemFlags,
    ) -> Result<Self> {
        let pitch_bytes = Self::pitch_bytes_for(device, width);
        debug_assert_eq!(pitch_bytes % size_of::<T>(), 0);
        let pitch = pitch_bytes / size_of::<T>();
        let buffer = ocl::Buffer::<T>::builder()
            .queue(device.queue.clone())
            .flags(flags)
            .len(pitch * height)
            .build()
            .map_err(|e| device_error(&device.info, "allocating the output image", e))?;
        Ok(PitchedBuffer {
            buffer,
            width,
            height,
            pitch,
        })
    }

    /// Reads the first `rows` rows into `out`, tightly packed (`width` elements a row),
    /// skipping the padding. Blocks until done (ocl's reads block by default).
    pub(crate) fn read_rows(&self, device: &ClDevice, rows: usize, out: &mut [T]) -> Result<()> {
        self.read_row_range(device, 0..rows, out)
    }

    /// Reads the rows `rows` into `out`, tightly packed, as [`PitchedBuffer::read_rows`].
    pub(crate) fn read_row_range(
        &self,
        device: &ClDevice,
        rows: std::ops::Range<usize>,
        out: &mut [T],
    ) -> Result<()> {
        assert!(
            rows.end <= self.height && out.len() >= rows.len() * self.width,
            "read_rows out of bounds"
        );
        if rows.is_empty() {
            return Ok(());
        }
        let size = size_of::<T>();
        self.buffer
            .cmd()
            .queue(&device.queue)
            .read(&mut out[..rows.len() * self.width])
            .rect(
                [0, rows.start, 0],
                [0, 0, 0],
                [self.width, rows.len(), 1],
                self.pitch * size,
                0,
                self.width * size,
                0,
            )
            .enq()
            .map_err(|e| device_error(&device.info, "reading the image back", e))
    }
}
