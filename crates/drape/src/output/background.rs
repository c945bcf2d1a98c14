//! Output work done on a thread of its own, in submission order.
//!
//! Writing a field frame is mostly waiting: [`super::atomic`] syncs every
//! file and its directory to disk before and after the rename that
//! publishes it. A run loop that waits for that does no mechanics in the
//! meantime, although the work is pure output and the next step does not
//! depend on it. [`Background`] runs such jobs on one scoped thread fed
//! through a bounded channel, so the loop only pays for handing over an
//! owned snapshot, and blocks only when the thread falls more than
//! `capacity` jobs behind (which bounds the memory held by snapshots).
//!
//! Jobs run one after the other in the order they were submitted, so a
//! job may rely on every earlier one being complete on disk — a frame is
//! written before the collection that names it, as on the calling
//! thread. A job that fails stops the thread; its error is returned by the
//! next [`Background::submit`], [`Background::flush`] or
//! [`Background::finish`], and the jobs queued behind it are dropped
//! unwritten. A panic in a job is resumed on the calling thread when it
//! next talks to the writer.
//!
//! The thread is scoped ([`std::thread::scope`]) so that jobs may borrow
//! what outlives the scope (the model, the output directory) instead of
//! cloning it; leaving the scope waits for the thread, so nothing is
//! still being written once the scope has returned.

use std::sync::mpsc::{self, Receiver, SyncSender, TryRecvError, TrySendError};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::{Duration, Instant};

/// What the calling thread sends: a job, or a request to say when every
/// job before it is done.
enum Message<J> {
    Job(J),
    Flush(SyncSender<()>),
}

/// A thread that runs output jobs of type `J` in submission order; a
/// failed job's error `E` comes back to the caller.
pub struct Background<'scope, J, E> {
    /// `None` once [`Background::finish`] has closed the channel.
    sender: Option<SyncSender<Message<J>>>,
    /// `None` once the thread has been joined (after an error or at the
    /// end).
    handle: Option<ScopedJoinHandle<'scope, Result<Duration, E>>>,
}

impl<'scope, J: Send + 'scope, E: Send + 'scope> Background<'scope, J, E> {
    /// Starts the thread `name` in `scope`; it runs `work` on each job
    /// submitted, and at most `capacity` jobs wait in the channel (at
    /// least one does) before [`Background::submit`] blocks.
    ///
    /// # Errors
    /// Any error of the operating system creating the thread.
    pub fn spawn<'env, F>(
        scope: &'scope Scope<'scope, 'env>,
        name: &str,
        capacity: usize,
        work: F,
    ) -> std::io::Result<Self>
    where
        F: FnMut(J) -> Result<(), E> + Send + 'scope,
    {
        let (sender, receiver) = mpsc::sync_channel(capacity.max(1));
        let handle = std::thread::Builder::new()
            .name(name.to_owned())
            .spawn_scoped(scope, move || serve(receiver, work))?;
        Ok(Self {
            sender: Some(sender),
            handle: Some(handle),
        })
    }

    /// Queues `job`, blocking while `capacity` jobs are already waiting.
    ///
    /// # Errors
    /// The error of an earlier job that failed (this one is then dropped).
    /// After an error has been returned the thread is gone and later jobs
    /// are dropped without one.
    pub fn submit(&mut self, job: J) -> Result<(), E> {
        if self.send(Message::Job(job)) {
            Ok(())
        } else {
            // The receiver is gone: the thread stopped on an error.
            self.join().map(|_| ())
        }
    }

    /// Waits until every job submitted so far is done (e.g. before a
    /// checkpoint records the frames as written).
    ///
    /// # Errors
    /// The error of a job that failed.
    pub fn flush(&mut self) -> Result<(), E> {
        if self.sender.is_none() {
            return Ok(());
        }
        let (reply, done) = mpsc::sync_channel(1);
        if !self.send(Message::Flush(reply)) {
            return self.join().map(|_| ());
        }
        let mut pause = Pause::default();
        loop {
            match done.try_recv() {
                Ok(()) => return Ok(()),
                // The thread stopped before answering: on an error.
                Err(TryRecvError::Disconnected) => return self.join().map(|_| ()),
                Err(TryRecvError::Empty) => pause.wait(),
            }
        }
    }

    /// Hands `message` to the thread, waiting while the channel is full;
    /// `false` when the thread is gone (or was joined).
    fn send(&mut self, mut message: Message<J>) -> bool {
        let Some(sender) = &self.sender else {
            return false;
        };
        let mut pause = Pause::default();
        loop {
            match sender.try_send(message) {
                Ok(()) => return true,
                Err(TrySendError::Full(m)) => {
                    message = m;
                    pause.wait();
                }
                Err(TrySendError::Disconnected(_)) => return false,
            }
        }
    }

    /// Waits for every job submitted, stops the thread and returns the
    /// time it spent in jobs.
    ///
    /// # Errors
    /// The error of a job that failed.
    pub fn finish(mut self) -> Result<Duration, E> {
        // Every job done first (waiting as `flush` does, free to serve
        // the thread pool), so that the join below does not wait on them.
        self.flush()?;
        // Closing the channel ends the thread's loop once it is empty.
        self.sender = None;
        self.join()
    }

    /// Joins the thread: its error, or the time it spent in jobs. A panic
    /// on the thread is resumed here.
    fn join(&mut self) -> Result<Duration, E> {
        // Without a sender nothing more can be submitted after an error.
        self.sender = None;
        match self.handle.take().map(ScopedJoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(panic)) => std::panic::resume_unwind(panic),
            // Joined before, and whatever it reported was returned then.
            None => Ok(Duration::ZERO),
        }
    }
}

/// How the calling thread waits for the writer: a rayon worker (the
/// command line's main thread is one) runs the pool's pending jobs
/// meanwhile — with one thread it is the pool's only worker, and a job
/// that uses the pool (the frame's element results on a large mesh) would
/// otherwise wait for it for ever while it waits for the job; any other
/// thread sleeps briefly between looks (20 µs, then 0.5 ms).
#[derive(Default)]
struct Pause {
    looks: u32,
}

impl Pause {
    fn wait(&mut self) {
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            return;
        }
        self.looks += 1;
        let micros = if self.looks < 50 { 20 } else { 500 };
        std::thread::sleep(Duration::from_micros(micros));
    }
}

/// The thread's loop: runs jobs in order until the channel closes or a
/// job fails, timing the jobs.
fn serve<J, E>(
    receiver: Receiver<Message<J>>,
    mut work: impl FnMut(J) -> Result<(), E>,
) -> Result<Duration, E> {
    let mut busy = Duration::ZERO;
    for message in receiver {
        match message {
            Message::Job(job) => {
                let start = Instant::now();
                let result = work(job);
                busy += start.elapsed();
                result?;
            }
            Message::Flush(reply) => {
                // The caller waits for this; it cannot have gone away.
                let _ = reply.send(());
            }
        }
    }
    Ok(busy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::atomic::write_atomic;
    use std::path::{Path, PathBuf};
    use std::sync::Mutex;

    fn test_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "drape-output-background-{}-{}",
            name,
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Jobs run in submission order, on another thread, and all of them
    /// are done when `flush` and `finish` return — even with a channel of
    /// one so that submissions block behind slow jobs.
    #[test]
    fn jobs_run_in_order_and_are_done_after_flush_and_finish() {
        let done = Mutex::new(Vec::new());
        let caller = std::thread::current().id();
        std::thread::scope(|scope| {
            let mut writer = Background::spawn(scope, "test-writer", 1, |k: usize| {
                assert_ne!(std::thread::current().id(), caller);
                // Slow early jobs: later ones must still wait their turn.
                std::thread::sleep(Duration::from_millis(if k < 5 { 5 } else { 0 }));
                done.lock().unwrap().push(k);
                Ok::<(), String>(())
            })
            .unwrap();
            for k in 0..20 {
                writer.submit(k).unwrap();
            }
            writer.flush().unwrap();
            assert_eq!(*done.lock().unwrap(), (0..20).collect::<Vec<_>>());
            for k in 20..40 {
                writer.submit(k).unwrap();
            }
            let busy = writer.finish().unwrap();
            // Five jobs slept 5 ms each.
            assert!(busy >= Duration::from_millis(25), "{busy:?}");
        });
        assert_eq!(done.into_inner().unwrap(), (0..40).collect::<Vec<_>>());
    }

    /// A write into a directory that does not exist fails on the thread;
    /// the error (naming the path) comes back from a later submission or
    /// from `finish`, the jobs before it are on disk and none after it
    /// ran.
    #[test]
    fn an_error_on_the_thread_comes_back_with_its_path() {
        let dir = test_dir("error");
        let write = |path: PathBuf| {
            write_atomic(&path, b"frame").map_err(|e| format!("{}: {e}", path.display()))
        };
        let bad = dir.join("missing").join("frame_2");
        let error = std::thread::scope(|scope| {
            let mut writer = Background::spawn(scope, "test-writer", 1, write).unwrap();
            for k in 0..2 {
                writer.submit(dir.join(format!("frame_{k}"))).unwrap();
            }
            writer.submit(bad.clone()).unwrap();
            // The failure is reported by one of the next calls, at the
            // latest by `finish`.
            let mut error = None;
            for k in 3..100 {
                if let Err(e) = writer.submit(dir.join(format!("frame_{k}"))) {
                    error = Some(e);
                    break;
                }
            }
            // After the error, the writer accepts and drops submissions.
            assert!(writer.submit(dir.join("late")).is_ok());
            assert!(writer.flush().is_ok());
            match error {
                Some(e) => {
                    assert!(writer.finish().is_ok());
                    e
                }
                None => writer.finish().unwrap_err(),
            }
        });
        assert!(error.starts_with(&bad.display().to_string()), "{error}");
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["frame_0", "frame_1"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// `flush` reports an error of a job submitted before it.
    #[test]
    fn flush_reports_the_error_of_an_earlier_job() {
        std::thread::scope(|scope| {
            let mut writer = Background::spawn(scope, "test-writer", 4, |p: &Path| {
                if p.ends_with("bad") {
                    Err(p.display().to_string())
                } else {
                    Ok(())
                }
            })
            .unwrap();
            writer.submit(Path::new("good")).unwrap();
            writer.submit(Path::new("bad")).unwrap();
            assert_eq!(writer.flush().unwrap_err(), "bad");
            assert!(writer.finish().is_ok());
        });
    }

    /// A panic in a job is not lost: it reaches the caller.
    #[test]
    fn a_panic_on_the_thread_reaches_the_caller() {
        let result = std::panic::catch_unwind(|| {
            std::thread::scope(|scope| {
                let mut writer = Background::spawn(scope, "test-writer", 1, |k: usize| {
                    assert!(k < 1, "job {k} panics");
                    Ok::<(), ()>(())
                })
                .unwrap();
                writer.submit(0).unwrap();
                writer.submit(1).unwrap();
                let _ = writer.finish();
            })
        });
        assert!(result.is_err());
    }
}
