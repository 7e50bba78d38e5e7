//! Reading GPU buffers back to the CPU, waiting for the GPU: [`read_buffer`] copies into a
//! staging buffer ([`copy_to_staging`]) and maps it; [`map_buffer`] maps a MAP_READ buffer
//! already filled. (The
//! window's surface counters are read without waiting; see `render::surface::pass`.)

use thiserror::Error;

#[derive(Debug, Error)]
pub enum ReadbackError {
    /// `what` names the data (a buffer's label, "the rendered image"), `reason` wgpu's words.
    #[error("reading {what} back from the GPU failed: {reason}")]
    Map { what: String, reason: String },
}

/// Copies `size` bytes from the start of `source` (which needs COPY_SRC) into a staging buffer
/// labelled `label`, submits, waits and returns them. Zero bytes return at once.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    source: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, ReadbackError> {
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = copy_to_staging(device, queue, label, source, size);
    map_buffer(device, &staging, label)
}

/// Copies `size` (> 0) bytes from the start of `source` (which needs COPY_SRC) into a new
/// MAP_READ staging buffer labelled `label` and submits the copy, without waiting: the caller
/// maps the buffer as it waits best ([`map_buffer`] blocks).
pub fn copy_to_staging(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    source: &wgpu::Buffer,
    size: u64,
) -> wgpu::Buffer {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    staging
}

/// Maps a MAP_READ buffer after the queue's work is done and returns a copy of its bytes;
/// `what` names the data in the error.
pub fn map_buffer(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    what: &str,
) -> Result<Vec<u8>, ReadbackError> {
    map_buffer_with(device, buffer, what, <[u8]>::to_vec)
}

/// Maps a MAP_READ buffer after the queue's work is done, hands its bytes to `read` and unmaps
/// it, so a buffer read every frame is reused and its bytes copied once, where the caller
/// wants them; `what` names the data in the error.
pub fn map_buffer_with<R>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    what: &str,
    read: impl FnOnce(&[u8]) -> R,
) -> Result<R, ReadbackError> {
    map_buffer_after(device, buffer, None, what, read)
}

/// [`map_buffer_with`] waiting only for the submission `index` (the one that filled the
/// buffer), not for work submitted after it: a video keeps the next frame drawing while it
/// reads this one. `None` waits for everything submitted.
pub fn map_buffer_after<R>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    index: Option<wgpu::SubmissionIndex>,
    what: &str,
    read: impl FnOnce(&[u8]) -> R,
) -> Result<R, ReadbackError> {
    let failed = |reason: String| ReadbackError::Map {
        what: what.to_string(),
        reason,
    };
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device
        .poll(wgpu::PollType::Wait {
            submission_index: index,
            timeout: None,
        })
        .map_err(|e| failed(e.to_string()))?;
    receiver
        .recv()
        .map_err(|e| failed(e.to_string()))?
        .map_err(|e| failed(e.to_string()))?;
    let out = {
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| failed(e.to_string()))?;
        read(&bytes)
    };
    buffer.unmap();
    Ok(out)
}
