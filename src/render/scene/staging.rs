//! How the world's and the lights' data reach their GPU buffers (the moving objects write their two fixed-size
//! buffers directly, the counters are a `ShaderBuffer` asset): a `Staging` queue per buffer takes whole contents
//! or element ranges in the order the main world produced them, and turns them into the buffer operations that leave the
//! GPU copy equal to the CPU source. What to write (`Staging::ops`) is pure, so it is tested without a GPU;
//! `upload` runs the operations with wgpu.

use super::storage_buffer;
use bevy::render::render_resource::Buffer;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bytemuck::Pod;
use std::sync::Arc;

/// When a buffer can take whole new contents in place instead of being created again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    /// Only at the same size: the shaders read the buffer's length (`arrayLength`) or index all of it.
    Exact,
    /// Whenever the contents fit: the shaders only read what the contents say is there.
    AtLeast,
}

/// One step that brings a buffer in line with its queue.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferOp<'a> {
    /// Create the buffer with these bytes (the following writes go to it).
    Create(&'a [u8]),
    /// Overwrite bytes from `offset`.
    Write { offset: u64, bytes: &'a [u8] },
}

/// Uploads queued for one buffer, merged as they arrive: whole contents supersede everything queued before them,
/// ranges queued after whole contents apply on top of them.
#[derive(Debug)]
pub struct Staging<T> {
    whole: Option<Arc<Vec<T>>>,
    /// (first element, elements), in queue order: a later range wins where two overlap.
    ranges: Vec<(u64, Vec<T>)>,
}

impl<T> Default for Staging<T> {
    fn default() -> Self {
        Staging { whole: None, ranges: Vec::new() }
    }
}

impl<T: Pod> Staging<T> {
    /// Queues the buffer's whole new contents (its length may differ from the buffer's).
    pub fn whole(&mut self, contents: Arc<Vec<T>>) {
        self.whole = Some(contents);
        self.ranges.clear();
    }

    /// Queues `elements` to overwrite the buffer from element `first` on.
    pub fn range(&mut self, first: u64, elements: &[T]) {
        self.ranges.push((first, elements.to_vec()));
    }

    pub fn is_empty(&self) -> bool {
        self.whole.is_none() && self.ranges.is_empty()
    }

    /// Whether whole contents are queued (a buffer that does not exist yet can be created).
    pub fn has_whole(&self) -> bool {
        self.whole.is_some()
    }

    /// Bytes the queued uploads carry.
    pub fn bytes(&self) -> u64 {
        let elements =
            self.whole.as_ref().map_or(0, |w| w.len()) + self.ranges.iter().map(|r| r.1.len()).sum::<usize>();
        (elements * size_of::<T>()) as u64
    }

    /// The operations that bring a buffer of `current` bytes (`None`: no buffer yet) to the queued contents.
    /// Without whole contents and without a buffer there is nothing the ranges could land in: no operations.
    pub fn ops(&self, current: Option<u64>, fit: Fit) -> Vec<BufferOp<'_>> {
        let mut ops = Vec::with_capacity(self.ranges.len() + 1);
        match (&self.whole, current) {
            (None, None) => return ops,
            (None, Some(_)) => {}
            (Some(whole), Some(size)) if fits(size, whole.len() * size_of::<T>(), fit) => {
                ops.push(BufferOp::Write { offset: 0, bytes: bytemuck::cast_slice(whole) });
            }
            (Some(whole), _) => ops.push(BufferOp::Create(bytemuck::cast_slice(whole))),
        }
        ops.extend(self.ranges.iter().map(|(first, elements)| BufferOp::Write {
            offset: first * size_of::<T>() as u64,
            bytes: bytemuck::cast_slice(elements),
        }));
        ops
    }

    /// Forgets what is queued (once written).
    pub fn clear(&mut self) {
        self.whole = None;
        self.ranges.clear();
    }
}

fn fits(buffer_bytes: u64, content_bytes: usize, fit: Fit) -> bool {
    match fit {
        Fit::Exact => buffer_bytes == content_bytes as u64,
        Fit::AtLeast => buffer_bytes >= content_bytes as u64,
    }
}

/// A CPU-owned GPU buffer's name and how whole new contents fit it.
#[derive(Clone, Copy, Debug)]
pub struct Mirrored {
    pub label: &'static str,
    pub fit: Fit,
}

/// Writes what `staging` holds into `current` (or a buffer created for it) and empties the queue. Returns the
/// buffer when one was created.
pub fn upload<T: Pod>(
    staging: &mut Staging<T>,
    current: Option<&Buffer>,
    mirrored: Mirrored,
    device: &RenderDevice,
    queue: &RenderQueue,
) -> Option<Buffer> {
    let mut created: Option<Buffer> = None;
    for op in staging.ops(current.map(|b| b.size()), mirrored.fit) {
        match op {
            BufferOp::Create(bytes) => created = Some(storage_buffer(device, mirrored.label, bytes)),
            BufferOp::Write { offset, bytes } => {
                if let Some(target) = created.as_ref().or(current) {
                    queue.write_buffer(target, offset, bytes);
                }
            }
        }
    }
    staging.clear();
    created
}

/// Brings `buffer` in line with `staging` (swapping in a new buffer where the contents no longer fit it) and
/// says whether it was created again: bind groups over it must then be made again.
pub fn sync<T: Pod>(
    staging: &mut Staging<T>,
    buffer: &mut Buffer,
    mirrored: Mirrored,
    device: &RenderDevice,
    queue: &RenderQueue,
) -> bool {
    let created = upload(staging, Some(buffer), mirrored, device, queue);
    created.map(|new| *buffer = new).is_some()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Runs `ops` on a CPU stand-in for the GPU buffer (`None`: not created yet), the way `upload` runs them.
    pub(crate) fn run(ops: &[BufferOp], gpu: &mut Option<Vec<u8>>) {
        for op in ops {
            match *op {
                BufferOp::Create(bytes) => *gpu = Some(bytes.to_vec()),
                BufferOp::Write { offset, bytes } => {
                    let buffer = gpu.as_mut().expect("a write needs a buffer");
                    let start = offset as usize;
                    assert!(start + bytes.len() <= buffer.len(), "write past the buffer's end");
                    buffer[start..start + bytes.len()].copy_from_slice(bytes);
                }
            }
        }
    }

    /// One change to the CPU source.
    #[derive(Clone, Debug)]
    enum Change {
        Whole(Vec<u32>),
        Range(u64, Vec<u32>),
    }

    fn changes() -> Vec<Change> {
        vec![
            // Grows the buffer, then shrinks it; the ranges fit the shortest contents.
            Change::Whole((100..108).collect()),
            Change::Whole(vec![7, 8, 9]),
            Change::Range(1, vec![21, 22]),
            Change::Range(0, vec![31]),
            Change::Range(2, vec![41]),
        ]
    }

    /// Every order of `items`.
    pub(crate) fn permutations<T: Clone>(items: &[T]) -> Vec<Vec<T>> {
        if items.is_empty() {
            return vec![Vec::new()];
        }
        let mut out = Vec::new();
        for i in 0..items.len() {
            let mut rest = items.to_vec();
            let first = rest.remove(i);
            for mut tail in permutations(&rest) {
                tail.insert(0, first.clone());
                out.push(tail);
            }
        }
        out
    }

    /// Applies `change` to the CPU source and queues the matching upload.
    fn change_and_queue(change: &Change, source: &mut Vec<u32>, staging: &mut Staging<u32>) {
        match change {
            Change::Whole(contents) => {
                *source = contents.clone();
                staging.whole(Arc::new(contents.clone()));
            }
            Change::Range(first, elements) => {
                let start = *first as usize;
                source[start..start + elements.len()].copy_from_slice(elements);
                staging.range(*first, elements);
            }
        }
    }

    fn drain(staging: &mut Staging<u32>, gpu: &mut Option<Vec<u8>>, fit: Fit) {
        let ops = staging.ops(gpu.as_ref().map(|b| b.len() as u64), fit);
        run(&ops, gpu);
        staging.clear();
    }

    /// The GPU copy holds the source's bytes: exactly, or as a prefix where the buffer may be larger.
    fn assert_matches(gpu: &Option<Vec<u8>>, source: &[u32], fit: Fit, order: &[Change]) {
        let gpu = gpu.as_ref().expect("a buffer exists");
        let expected: &[u8] = bytemuck::cast_slice(source);
        match fit {
            Fit::Exact => assert_eq!(gpu.as_slice(), expected, "{fit:?} after {order:?}"),
            Fit::AtLeast => assert_eq!(&gpu[..expected.len()], expected, "{fit:?} after {order:?}"),
        }
    }

    /// Every order of whole and partial uploads, drained in one go or split at every point, starting with no
    /// buffer (the first whole upload creates it) or with one that already holds the source.
    #[test]
    fn every_order_of_whole_and_partial_uploads_leaves_the_source_bytes() {
        let initial: Vec<u32> = vec![1, 2, 3, 4];
        for fit in [Fit::Exact, Fit::AtLeast] {
            for order in permutations(&changes()) {
                for split in 0..=order.len() {
                    for created_before in [false, true] {
                        let mut source = initial.clone();
                        let mut staging = Staging::default();
                        let mut gpu = None;
                        if created_before {
                            gpu = Some(bytemuck::cast_slice(&initial).to_vec());
                        } else {
                            staging.whole(Arc::new(initial.clone()));
                        }
                        for change in &order[..split] {
                            change_and_queue(change, &mut source, &mut staging);
                        }
                        drain(&mut staging, &mut gpu, fit);
                        assert_matches(&gpu, &source, fit, &order[..split]);
                        for change in &order[split..] {
                            change_and_queue(change, &mut source, &mut staging);
                        }
                        drain(&mut staging, &mut gpu, fit);
                        assert_matches(&gpu, &source, fit, &order);
                    }
                }
            }
        }
    }

    #[test]
    fn whole_contents_are_written_in_place_only_when_they_fit() {
        let mut staging = Staging::default();
        staging.whole(Arc::new(vec![5u32, 6]));
        let bytes: &[u8] = bytemuck::cast_slice(&[5u32, 6]);
        assert_eq!(staging.ops(None, Fit::AtLeast), vec![BufferOp::Create(bytes)]);
        assert_eq!(staging.ops(Some(8), Fit::Exact), vec![BufferOp::Write { offset: 0, bytes }]);
        assert_eq!(staging.ops(Some(16), Fit::Exact), vec![BufferOp::Create(bytes)]);
        assert_eq!(staging.ops(Some(16), Fit::AtLeast), vec![BufferOp::Write { offset: 0, bytes }]);
        assert_eq!(staging.ops(Some(4), Fit::AtLeast), vec![BufferOp::Create(bytes)]);
    }

    #[test]
    fn ranges_without_a_buffer_or_whole_contents_have_nowhere_to_go() {
        let mut staging = Staging::default();
        staging.range(0, &[1u32]);
        assert!(staging.ops(None, Fit::Exact).is_empty());
        assert_eq!(staging.ops(Some(4), Fit::Exact).len(), 1);
    }
}
