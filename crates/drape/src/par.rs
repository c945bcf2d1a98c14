//! Fork–join on two threads for work too fine for rayon: a process-wide
//! helper thread that spins for the next task.
//!
//! The loops of a small model (the 20x20 pedestal: 800 elements, 441
//! nodes) are short and run thousands of times per run. Handing such a
//! loop to rayon costs more than it saves on a virtual machine: an idle
//! rayon worker goes to sleep after a few dozen yields, and waking it (a
//! futex and an interrupt to a halted virtual CPU) costs more than the
//! loop, where a thread that spins takes the task at once (the figures:
//! docs/performance.md, "The round before"). [`join`] hands its second closure to one
//! helper thread that spins for up to [`SPIN`] after its last task and
//! then parks, so a run keeps it awake and an idle process costs nothing.
//!
//! Whoever gets there first runs the second closure: the caller takes it
//! back when the helper has not claimed it by the time the first one is
//! done. The split of the work is the caller's, so results never depend on
//! which thread ran what. One caller at a time uses the helper (joins
//! from other threads, and joins nested in a join, run both closures on
//! the calling thread), and a machine with one core has no helper, nor a
//! run with `RAYON_NUM_THREADS=1`.

use std::cell::UnsafeCell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicPtr, Ordering};
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

/// How long the helper spins for a task after its last one before it
/// parks: longer than the gaps between the split loops of one Newton
/// iteration of a small model (tens of microseconds on the pedestal), far
/// shorter than the serial work between a larger model's loops (the
/// bending assembly of a mid-size fabric, milliseconds), during which the
/// helper used to spin away a core: 100 us instead of 2 ms left the
/// pedestal's wall time unchanged (ratio 0.99, 7 runs each) and took the
/// settle benchmark's CPU time from 26.4 to 21.7 s at the same wall time
/// (docs/performance.md, "A helper that does not spin").
pub const SPIN: Duration = Duration::from_micros(100);

/// A task published to the helper: the closure's state and how to run it.
struct JobRef {
    data: *const (),
    execute: unsafe fn(*const ()),
}

/// The second closure of a [`join`], on the caller's stack.
struct StackJob<B, R> {
    func: UnsafeCell<Option<B>>,
    result: UnsafeCell<Option<thread::Result<R>>>,
    done: AtomicBool,
}

impl<B: FnOnce() -> R, R> StackJob<B, R> {
    /// Runs the closure once, wherever called; `done` is the last write.
    ///
    /// # Safety
    /// `this` points to a live `StackJob<B, R>` whose closure has not been
    /// taken, and no other thread touches `func` or `result` until `done`.
    unsafe fn execute(this: *const ()) {
        // SAFETY: per the contract above.
        unsafe {
            let job = &*(this as *const Self);
            let f = (*job.func.get()).take().expect("a job runs once");
            *job.result.get() = Some(panic::catch_unwind(AssertUnwindSafe(f)));
            job.done.store(true, Ordering::Release);
        }
    }
}

struct Team {
    /// The published task, null when none.
    slot: AtomicPtr<JobRef>,
    /// Held by the caller of a `join` (one at a time).
    busy: AtomicBool,
    /// The helper is parked or about to park.
    sleeping: AtomicBool,
    helper: Thread,
}

fn team() -> Option<&'static Team> {
    static TEAM: OnceLock<Option<&'static Team>> = OnceLock::new();
    *TEAM.get_or_init(|| {
        // One core, or one thread asked for (as rayon reads it): no helper.
        let threads = std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            .filter(|&t| t > 0)
            .unwrap_or_else(|| thread::available_parallelism().map_or(1, |n| n.get()));
        if threads < 2 {
            return None;
        }
        let (tx, rx) = std::sync::mpsc::channel::<&'static Team>();
        let spawned = thread::Builder::new()
            .name("drape-helper".into())
            .spawn(move || {
                let Ok(team) = rx.recv() else { return };
                serve(team);
            })
            .ok()?;
        let team: &'static Team = Box::leak(Box::new(Team {
            slot: AtomicPtr::new(std::ptr::null_mut()),
            busy: AtomicBool::new(false),
            sleeping: AtomicBool::new(false),
            helper: spawned.thread().clone(),
        }));
        tx.send(team).ok()?;
        Some(team)
    })
}

/// The helper's loop: claim and run tasks, spin between them, park when
/// idle for [`SPIN`].
fn serve(team: &Team) {
    loop {
        let mut idle_since = Instant::now();
        let mut spins = 0u32;
        loop {
            let p = team.slot.load(Ordering::Acquire);
            if !p.is_null() {
                if team
                    .slot
                    .compare_exchange(p, std::ptr::null_mut(), Ordering::AcqRel, Ordering::Acquire)
                    .is_ok()
                {
                    // SAFETY: the caller keeps the `JobRef` and its job alive
                    // until the job's `done`, which `execute` writes last;
                    // claiming the slot made this thread the only runner.
                    unsafe {
                        let job = &*p;
                        (job.execute)(job.data);
                    }
                }
                idle_since = Instant::now();
                spins = 0;
                continue;
            }
            std::hint::spin_loop();
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(256) {
                // Leave the core to other threads now and then (the frame
                // writer), and park when idle long enough.
                thread::yield_now();
                if idle_since.elapsed() > SPIN {
                    break;
                }
            }
        }
        team.sleeping.store(true, Ordering::SeqCst);
        if team.slot.load(Ordering::SeqCst).is_null() {
            thread::park();
        }
        team.sleeping.store(false, Ordering::SeqCst);
    }
}

/// Whether [`join`] may run its closures on two threads (the machine has
/// two cores or more and the helper thread could be started).
pub fn helper_available() -> bool {
    team().is_some()
}

/// Runs `a` on the calling thread and `b` on the helper thread, or both
/// here when the helper is busy, absent or late; returns both results.
/// A panic in either closure resumes on the caller once both are done.
pub fn join<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
where
    A: FnOnce() -> RA,
    B: FnOnce() -> RB + Send,
    RB: Send,
{
    let Some(team) = team().filter(|t| {
        t.busy
            .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
    }) else {
        // Both here; a panic in `a` still lets `b` run first, as on two
        // threads (with the helper busy in another test or caller, `b`
        // was skipped and the promise above broken).
        let ra = panic::catch_unwind(AssertUnwindSafe(a));
        let rb = b();
        return match ra {
            Ok(ra) => (ra, rb),
            Err(e) => panic::resume_unwind(e),
        };
    };
    let job = StackJob {
        func: UnsafeCell::new(Some(b)),
        result: UnsafeCell::new(None),
        done: AtomicBool::new(false),
    };
    let job_ref = JobRef {
        data: &job as *const StackJob<B, RB> as *const (),
        execute: StackJob::<B, RB>::execute,
    };
    let p = &job_ref as *const JobRef as *mut JobRef;
    team.slot.store(p, Ordering::SeqCst);
    if team.sleeping.load(Ordering::SeqCst) {
        team.helper.unpark();
    }
    let ra = panic::catch_unwind(AssertUnwindSafe(a));
    if team
        .slot
        .compare_exchange(p, std::ptr::null_mut(), Ordering::AcqRel, Ordering::Acquire)
        .is_ok()
    {
        // Not claimed: run it here.
        // SAFETY: the job is alive and no other thread can claim it now.
        unsafe { StackJob::<B, RB>::execute(job_ref.data) };
    } else {
        let mut spins = 0u32;
        while !job.done.load(Ordering::Acquire) {
            std::hint::spin_loop();
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(1024) {
                thread::yield_now();
            }
        }
    }
    team.busy.store(false, Ordering::Release);
    let rb = job.result.into_inner().expect("the job ran before `done`");
    match (ra, rb) {
        (Ok(ra), Ok(rb)) => (ra, rb),
        (Err(e), _) | (_, Err(e)) => panic::resume_unwind(e),
    }
}

/// `f` over the two halves of `0..len`, the second half on the helper
/// thread ([`join`]): `(f(0..len / 2), f(len / 2..len))`.
pub fn halves<T, F>(len: usize, f: F) -> (T, T)
where
    T: Send,
    F: Fn(std::ops::Range<usize>) -> T + Sync,
{
    let mid = len / 2;
    join(|| f(0..mid), || f(mid..len))
}

/// A raw pointer shared by the threads of one colour of a parallel
/// assembly; sound because the elements (or stencils) of a colour touch
/// disjoint entries.
#[derive(Clone, Copy)]
pub(crate) struct Shared(pub(crate) *mut f64);
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    /// # Safety
    /// `k` is in bounds and no other thread writes entry `k` concurrently.
    #[inline]
    pub(crate) unsafe fn add(self, k: usize, v: f64) {
        unsafe { *self.0.add(k) += v }
    }

    /// # Safety
    /// As [`Shared::add`].
    #[inline]
    pub(crate) unsafe fn set(self, k: usize, v: f64) {
        unsafe { *self.0.add(k) = v }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn join_returns_both_results_and_writes_disjoint_halves() {
        let mut data = vec![0u64; 10_000];
        for round in 0..2_000u64 {
            let (lo, hi) = data.split_at_mut(5_000);
            let (a, b) = join(
                || {
                    lo.iter_mut().for_each(|x| *x += round);
                    lo.len()
                },
                || {
                    hi.iter_mut().for_each(|x| *x += 2 * round);
                    hi.len()
                },
            );
            assert_eq!((a, b), (5_000, 5_000));
        }
        let s: u64 = (0..2_000).sum();
        assert!(data[..5_000].iter().all(|&x| x == s));
        assert!(data[5_000..].iter().all(|&x| x == 2 * s));
    }

    #[test]
    fn joins_from_many_threads_and_nested_joins_all_run() {
        let count = AtomicUsize::new(0);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    for _ in 0..500 {
                        join(
                            || {
                                join(
                                    || count.fetch_add(1, Ordering::Relaxed),
                                    || count.fetch_add(1, Ordering::Relaxed),
                                )
                            },
                            || count.fetch_add(1, Ordering::Relaxed),
                        );
                    }
                });
            }
        });
        assert_eq!(count.load(Ordering::Relaxed), 4 * 500 * 3);
    }

    #[test]
    fn a_panic_in_either_closure_reaches_the_caller_after_both_ran() {
        for first in [true, false] {
            let ran = AtomicUsize::new(0);
            let caught = panic::catch_unwind(AssertUnwindSafe(|| {
                join(
                    || {
                        ran.fetch_add(1, Ordering::SeqCst);
                        if first {
                            panic!("first");
                        }
                    },
                    || {
                        ran.fetch_add(1, Ordering::SeqCst);
                        if !first {
                            panic!("second");
                        }
                    },
                )
            }));
            assert!(caught.is_err());
            assert_eq!(ran.load(Ordering::SeqCst), 2);
            // The helper is free again.
            assert_eq!(join(|| 1, || 2), (1, 2));
        }
    }

    #[test]
    fn the_helper_wakes_from_parking() {
        if !helper_available() {
            return;
        }
        std::thread::sleep(SPIN * 3);
        let on = std::thread::current().id();
        // (Other tests may hold the helper for a while: try for 2 s.)
        let start = Instant::now();
        let mut elsewhere = false;
        while !elsewhere && start.elapsed() < Duration::from_secs(2) {
            let (_, id) = join(
                || std::thread::sleep(Duration::from_micros(200)),
                || std::thread::current().id(),
            );
            elsewhere |= id != on;
        }
        assert!(elsewhere, "the helper never ran a task");
    }
}
