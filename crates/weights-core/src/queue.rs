//! The priority queue of the graph searches (Dijkstra's algorithm on the sample graph).
//!
//! Every edge of the graph is at least `min` long, so a search that has reached
//! distance d only ever queues distances from d + `min` on. Entries are therefore kept
//! in buckets of width `min / 2` (Dial's algorithm): everything in the current bucket
//! is final whatever order it comes out in, since no entry of a bucket can improve
//! another one of the same bucket. A ring of buckets covers the next longest edge;
//! entries beyond it, and everything queued before the first pop (the seeds of a search,
//! at any distances), wait in a binary heap. Pushing and popping cost a few
//! instructions instead of a heap's logarithmic sift with unpredictable branches.
//!
//! A graph whose edge lengths differ by more than [`MAX_BUCKETS`] / 2 uses the heap
//! alone. Either way the searches find the same distances, owners and tie-breaks as
//! with a heap: only the order among entries of one bucket differs, and those are final.

use std::collections::BinaryHeap;

/// The most buckets a ring may have.
const MAX_BUCKETS: usize = 1 << 12;

/// A queue entry: tentative distance, the tie-break key of its node, the sample, packed
/// into one integer so that a heap compares them in one instruction. Distances are
/// never negative, so their IEEE bit patterns order like the numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Entry(std::cmp::Reverse<u128>);

impl Entry {
    /// Sample `v` at tentative distance `d` (not negative), for the node whose
    /// tie-break key is `key`.
    #[inline]
    pub fn new(d: f64, key: u32, v: u32) -> Self {
        debug_assert!(d >= 0.0);
        Self(std::cmp::Reverse(
            (u128::from(d.to_bits()) << 64) | (u128::from(key) << 32) | u128::from(v),
        ))
    }

    /// The tentative distance.
    #[inline]
    pub fn d(&self) -> f64 {
        f64::from_bits((self.0.0 >> 64) as u64)
    }

    /// The tie-break key of the node.
    #[inline]
    pub fn key(&self) -> u32 {
        (self.0.0 >> 32) as u32
    }

    /// The sample.
    #[inline]
    pub fn v(&self) -> u32 {
        self.0.0 as u32
    }
}

/// A monotone priority queue of [`Entry`]s (see the module documentation).
#[derive(Debug, Default)]
pub(crate) struct Queue {
    /// One over the bucket width (0: the heap alone).
    inv_width: f64,
    /// The buckets, a power of two of them, so that a bucket's slot is a mask away
    /// (no division per push and pop).
    ring: Vec<Vec<Entry>>,
    /// `ring.len() - 1`.
    mask: u64,
    /// The absolute index of the current bucket.
    base: u64,
    /// Entries in the ring.
    in_ring: usize,
    /// Entries beyond the ring, and all entries until the first pop.
    overflow: BinaryHeap<Entry>,
    /// Whether a pop has set `base` since the queue was last empty.
    started: bool,
    /// The edge lengths the ring was made for.
    made_for: (f64, f64),
}

impl Queue {
    /// An empty queue (the heap alone until [`Queue::prepare`]).
    pub const fn new() -> Self {
        Self {
            inv_width: 0.0,
            ring: Vec::new(),
            mask: 0,
            base: 0,
            in_ring: 0,
            overflow: BinaryHeap::new(),
            started: false,
            made_for: (0.0, 0.0),
        }
    }

    /// Sets the queue up, empty, for a graph with edges from `min` to `max` long.
    pub fn prepare(&mut self, min: f64, max: f64) {
        self.clear();
        if self.made_for == (min, max) {
            return;
        }
        self.made_for = (min, max);
        let width = min / 2.0;
        let buckets = (max / width).ceil() + 3.0;
        if width > 0.0 && buckets <= MAX_BUCKETS as f64 {
            self.inv_width = 1.0 / width;
            let buckets = (buckets as usize).next_power_of_two();
            self.ring = vec![Vec::new(); buckets];
            self.mask = buckets as u64 - 1;
        } else {
            self.inv_width = 0.0;
            self.ring = Vec::new();
            self.mask = 0;
        }
    }

    /// Empties the queue.
    pub fn clear(&mut self) {
        if self.in_ring > 0 {
            self.ring.iter_mut().for_each(Vec::clear);
        }
        self.in_ring = 0;
        self.overflow.clear();
        self.started = false;
    }

    #[inline]
    fn bucket(&self, d: f64) -> u64 {
        (d * self.inv_width) as u64
    }

    #[inline]
    pub fn push(&mut self, entry: Entry) {
        if self.started {
            // (Never below the current bucket but for rounding; the current one is as
            // good then.)
            let b = self.bucket(entry.d()).max(self.base);
            if b <= self.base + self.mask {
                self.ring[(b & self.mask) as usize].push(entry);
                self.in_ring += 1;
                return;
            }
        }
        self.overflow.push(entry);
    }

    #[inline]
    pub fn pop(&mut self) -> Option<Entry> {
        if self.ring.is_empty() {
            return self.overflow.pop();
        }
        if !self.started {
            self.base = self.bucket(self.overflow.peek()?.d());
            self.started = true;
            self.refill();
        }
        loop {
            if let Some(entry) = self.ring[(self.base & self.mask) as usize].pop() {
                self.in_ring -= 1;
                return Some(entry);
            }
            if self.in_ring == 0 {
                // Jump to the nearest waiting entry, if any.
                let Some(next) = self.overflow.peek() else {
                    self.started = false;
                    return None;
                };
                self.base = self.bucket(next.d());
            } else {
                self.base += 1;
            }
            self.refill();
        }
    }

    /// Moves the waiting entries that now fall inside the ring into it.
    fn refill(&mut self) {
        while let Some(next) = self.overflow.peek() {
            let b = self.bucket(next.d()).max(self.base);
            if b > self.base + self.mask {
                break;
            }
            let entry = self.overflow.pop().expect("peeked");
            self.ring[(b & self.mask) as usize].push(entry);
            self.in_ring += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pops everything, checking that no entry comes out more than one bucket width
    /// (of `min` / 2) before a smaller one.
    fn drain(q: &mut Queue, min: f64) -> Vec<f64> {
        let mut out = Vec::new();
        while let Some(e) = q.pop() {
            out.push(e.d());
        }
        for (i, &d) in out.iter().enumerate() {
            for &later in &out[i + 1..] {
                assert!(later > d - min / 2.0, "{later} after {d}");
            }
        }
        out
    }

    #[test]
    fn seeds_anywhere_then_searches_come_out_in_order() {
        let (min, max) = (0.5, 2.0);
        let mut q = Queue::new();
        q.prepare(min, max);
        // Seeds far apart (beyond the ring), in any order; the nearest comes out first
        // (3.4 lies a bucket further).
        for (i, d) in [40.0, 3.0, 17.5, 3.4, 900.0].into_iter().enumerate() {
            q.push(Entry::new(d, 0, i as u32));
        }
        let first = q.pop().expect("seeded");
        assert_eq!(first.d(), 3.0);
        // A search relaxes edges of lengths within [min, max].
        let mut popped = vec![first.d()];
        let mut pushed = 5;
        let mut rng = 12345u64;
        while let Some(e) = q.pop() {
            popped.push(e.d());
            if pushed < 400 && e.d() < 800.0 {
                for _ in 0..2 {
                    rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1);
                    let len = min + (max - min) * ((rng >> 33) as f64 / (1u64 << 31) as f64);
                    q.push(Entry::new(e.d() + len, 0, pushed));
                    pushed += 1;
                }
            }
        }
        assert_eq!(popped.len(), pushed as usize);
        // Every entry came out no earlier than a bucket before its turn.
        let mut best_later = f64::INFINITY;
        for &d in popped.iter().rev() {
            assert!(
                d < best_later + min / 2.0,
                "{d} came out before {best_later}"
            );
            best_later = best_later.min(d);
        }
        q.push(Entry::new(7.0, 0, 0));
        q.push(Entry::new(1.0, 0, 1));
        assert_eq!(drain(&mut q, min), vec![1.0, 7.0]);
    }

    #[test]
    fn widely_spread_edges_use_the_heap_alone() {
        let mut q = Queue::new();
        q.prepare(1e-6, 10.0);
        for d in [5.0, 1.0, 3.0, 2.0] {
            q.push(Entry::new(d, 0, 0));
        }
        assert_eq!(drain(&mut q, 0.0), vec![1.0, 2.0, 3.0, 5.0]);
    }
}
