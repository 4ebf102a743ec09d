//! Progress reports, and running a long job (a bake, a render) on its own workers while the
//! calling thread hears them.
//!
//! A host that is not Rust wants its progress callback called on the thread it called from
//! (Python holds its interpreter lock there; a C host's callback may touch its UI), and wants
//! to stop the job from that callback. [`relay`] runs the job on a scoped thread, inside a
//! pool of the asked size, and passes every report back over a channel; the C ABI and the
//! Python package both use it.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

/// Which stage is running and how far it is (from 0 to 1), for progress display.
pub type Progress<'a> = &'a (dyn Fn(&str, f32) + Sync);

/// Run `work` on `threads` workers (0: rayon's global pool, one per core).
pub fn on_threads<R: Send>(threads: usize, work: impl FnOnce() -> R + Send) -> Result<R> {
    if threads == 0 {
        return Ok(work());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Threads {
            count: threads,
            reason: e.to_string(),
        })?;
    Ok(pool.install(work))
}

/// Run `work(progress, cancel)` on `threads` workers (see [`on_threads`]) while this thread
/// passes each of its reports to `listen(stage, fraction)`; `listen` returning true sets
/// `cancel`, which the work reads to stop early. Returns the work's result and whether a stop
/// was asked: a stop asked on the last reports, after the work last looked at the flag, still
/// counts, since the caller said it does not want the result. A panic in the work is resumed
/// here.
pub fn relay<R: Send>(
    threads: usize,
    work: impl FnOnce(Progress, &AtomicBool) -> R + Send,
    mut listen: impl FnMut(&str, f32) -> bool,
) -> Result<(R, bool)> {
    let cancel = &AtomicBool::new(false);
    let (sender, receiver) = mpsc::channel::<(String, f32)>();
    let result = std::thread::scope(|scope| {
        // The worker owns the sender, so the channel closes when the work returns.
        let worker = scope.spawn(move || {
            let report = move |stage: &str, fraction: f32| {
                // The receiver outlives the work; a failed send only means nobody listens.
                let _ = sender.send((stage.to_owned(), fraction));
            };
            on_threads(threads, || work(&report, cancel))
        });
        // Ends when the work returns.
        for (stage, fraction) in receiver {
            if listen(&stage, fraction) {
                cancel.store(true, Ordering::Relaxed);
            }
        }
        match worker.join() {
            Ok(result) => result,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })?;
    Ok((result, cancel.load(Ordering::Relaxed)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_arrive_in_order_on_the_calling_thread() {
        let caller = std::thread::current().id();
        let mut heard = Vec::new();
        let (sum, stopped) = relay(
            2,
            |progress, _| {
                for k in 0..4 {
                    progress("stage", k as f32 / 4.0);
                }
                rayon::current_num_threads()
            },
            |stage, fraction| {
                assert_eq!(std::thread::current().id(), caller);
                heard.push((stage.to_owned(), fraction));
                false
            },
        )
        .expect("two workers");
        assert_eq!(sum, 2, "the work runs in a pool of the asked size");
        assert!(!stopped);
        let fractions: Vec<f32> = heard.iter().map(|h| h.1).collect();
        assert_eq!(fractions, [0.0, 0.25, 0.5, 0.75]);
    }

    #[test]
    fn a_listener_stops_the_work() {
        let (looked, stopped) = relay(
            1,
            |progress, cancel| {
                // Report until the listener's stop arrives (it answers the first report).
                let mut reports = 0;
                while !cancel.load(Ordering::Relaxed) && reports < 1_000_000 {
                    progress("stage", 0.0);
                    reports += 1;
                    std::thread::yield_now();
                }
                cancel.load(Ordering::Relaxed)
            },
            |_, _| true,
        )
        .expect("one worker");
        assert!(looked, "the work saw the stop");
        assert!(stopped);
    }
}
