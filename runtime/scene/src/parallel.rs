//! The worker pool that steps actors in parallel.
//!
//! Work is cut into small chunks that workers claim from a shared counter, so a slow actor
//! does not hold up a whole thread's share. Which thread steps which actor never changes
//! the result: every actor's tick reads only the previous tick's world.
//!
//! The calling thread is one of the workers; the others are helper threads started on
//! the first call that needs them and kept for the pool's life (a `rayon_core` pool).
//! Starting them anew on every call, as the pool did, cost a tenth of a tick of 100
//! actors on two threads (PERFORMANCE.md, "Stop 75").

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

/// Most actors per claimed chunk.
const CHUNK: usize = 16;
/// Fewest actors per claimed chunk.
const MIN_CHUNK: usize = 4;
/// Chunks per worker to aim for, so that the last chunks even out the workers' loads.
const CHUNKS_PER_WORKER: usize = 8;

/// Runs per-item work on up to `threads` threads: the caller's and kept helpers.
#[derive(Debug)]
pub struct WorkerPool {
    threads: usize,
    /// Actors per chunk, when fixed (tests spread even two actors over two threads).
    chunk: Option<usize>,
    /// The `threads - 1` helper threads, once a call has needed them; `None` inside when
    /// they could not be started (the work then runs on the calling thread alone).
    helpers: OnceLock<Option<rayon_core::ThreadPool>>,
}

impl WorkerPool {
    /// A pool of `threads` workers (the calling thread is one of them).
    pub fn new(threads: usize) -> Self {
        WorkerPool {
            threads: threads.max(1),
            chunk: None,
            helpers: OnceLock::new(),
        }
    }

    /// Cuts work into chunks of exactly `items` (at least 1), using every thread
    /// whenever there are at least as many chunks; `None` restores the automatic sizes.
    pub fn set_chunk(&mut self, items: Option<usize>) {
        self.chunk = items.map(|n| n.max(1));
    }

    /// The number of workers.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// The helper threads, started on the first call.
    fn helpers(&self) -> Option<&rayon_core::ThreadPool> {
        self.helpers
            .get_or_init(|| {
                rayon_core::ThreadPoolBuilder::new()
                    .num_threads(self.threads - 1)
                    .thread_name(|i| format!("troupe-worker-{}", i + 1))
                    .build()
                    .inspect_err(|e| {
                        tracing::warn!("could not start worker threads, stepping on one: {e}")
                    })
                    .ok()
            })
            .as_ref()
    }

    /// Calls `f(index, item)` once for every item.
    pub fn for_each<T: Send>(&self, items: &mut [T], f: impl Fn(usize, &mut T) + Sync) {
        let (workers, size) = match self.chunk {
            Some(size) => (self.threads.min(items.len().div_ceil(size)), size),
            None => (
                // A worker is worth waking only with a full chunk's worth of actors.
                self.threads.min(items.len().div_ceil(CHUNK)),
                // Smaller crowds get smaller chunks: 100 actors in chunks of 16 would
                // leave one worker with four chunks and the other with three.
                (items.len() / (self.threads * CHUNKS_PER_WORKER)).clamp(MIN_CHUNK, CHUNK),
            ),
        };
        let helpers = if workers > 1 { self.helpers() } else { None };
        let Some(helpers) = helpers else {
            for (i, item) in items.iter_mut().enumerate() {
                f(i, item);
            }
            return;
        };
        let chunks: Vec<Mutex<Option<&mut [T]>>> = items
            .chunks_mut(size)
            .map(|c| Mutex::new(Some(c)))
            .collect();
        let next = AtomicUsize::new(0);
        let run = || loop {
            let c = next.fetch_add(1, Ordering::Relaxed);
            let Some(slot) = chunks.get(c) else { break };
            let chunk = slot
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .take();
            if let Some(chunk) = chunk {
                for (k, item) in chunk.iter_mut().enumerate() {
                    f(c * size + k, item);
                }
            }
        };
        // The helpers' share is spawned into the scope, the caller's runs in place; the
        // scope returns when every share has, and passes on a helper's panic.
        helpers.in_place_scope(|s| {
            for _ in 1..workers {
                s.spawn(|_| run());
            }
            run();
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_item_once_with_its_index() {
        // Sizes that give one worker, small chunks, a ragged last chunk, full chunks.
        for count in [0, 1, 2, 10, 17, 100, 133, 1000] {
            for threads in [1, 2, 4] {
                for chunk in [None, Some(1), Some(3)] {
                    let mut items: Vec<(usize, u32)> = (0..count).map(|i| (i, 0)).collect();
                    let mut pool = WorkerPool::new(threads);
                    pool.set_chunk(chunk);
                    pool.for_each(&mut items, |i, item| {
                        assert_eq!(i, item.0);
                        item.1 += 1;
                    });
                    assert!(
                        items.iter().all(|(_, n)| *n == 1),
                        "{count} on {threads}, {chunk:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_fixed_chunk_of_one_uses_every_thread_for_two_items() {
        // Each item waits (up to 2 s) until both have started: only two threads both see it.
        let started = AtomicUsize::new(0);
        let mut met = [false; 2];
        let mut pool = WorkerPool::new(2);
        pool.set_chunk(Some(1));
        pool.for_each(&mut met, |_, met| {
            started.fetch_add(1, Ordering::SeqCst);
            let until = std::time::Instant::now() + std::time::Duration::from_secs(2);
            while started.load(Ordering::SeqCst) < 2 && std::time::Instant::now() < until {
                std::thread::yield_now();
            }
            *met = started.load(Ordering::SeqCst) == 2;
        });
        assert_eq!(met, [true, true]);
    }
}
