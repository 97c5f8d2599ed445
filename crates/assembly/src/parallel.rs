//! Independent pieces of work on several threads, with the results (and the error) a loop
//! in order on one thread would give.

use std::sync::atomic::{AtomicUsize, Ordering};

/// The thread count `threads` asks for: 0 is as many as the machine has.
pub fn thread_count(threads: usize) -> usize {
    match threads {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    }
}

/// `work(j)` for every j in 0..n on up to `threads` threads (0: as many as the machine
/// has), the results in j order. Each j is computed exactly as on one thread (the numbers
/// do not depend on the thread count); on errors the one of the smallest j is returned, as
/// a loop in order would, and no j after it is started.
pub fn in_parallel<T: Send, E: Send>(
    n: usize,
    threads: usize,
    work: impl Fn(usize) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E> {
    let threads = thread_count(threads).clamp(1, n.max(1));
    if threads == 1 {
        return (0..n).map(work).collect();
    }
    let next = AtomicUsize::new(0);
    let first_error = AtomicUsize::new(usize::MAX);
    let mut slots: Vec<Option<Result<T, E>>> = (0..n).map(|_| None).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let j = next.fetch_add(1, Ordering::Relaxed);
                        if j >= n || j > first_error.load(Ordering::Relaxed) {
                            break;
                        }
                        let result = work(j);
                        if result.is_err() {
                            first_error.fetch_min(j, Ordering::Relaxed);
                        }
                        done.push((j, result));
                    }
                    done
                })
            })
            .collect();
        for worker in workers {
            match worker.join() {
                Ok(done) => {
                    for (j, result) in done {
                        slots[j] = Some(result);
                    }
                }
                // a panic is a bug: carry it on as a loop on this thread would
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
    });
    let mut out = Vec::with_capacity(n);
    for (j, slot) in slots.into_iter().enumerate() {
        match slot {
            Some(result) => out.push(result?),
            // not started, which only follows an error of a smaller j (returned above);
            // done here rather than assumed
            None => out.push(work(j)?),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_in_order_and_the_first_error_whatever_the_threads() {
        for threads in [1, 2, 5] {
            let squares = in_parallel(7, threads, |j| Ok::<_, String>(j * j));
            assert_eq!(squares, Ok(vec![0, 1, 4, 9, 16, 25, 36]));
            let failing = in_parallel(9, threads, |j| {
                if j == 3 || j == 6 {
                    Err(format!("failed at {j}"))
                } else {
                    Ok(j)
                }
            });
            assert_eq!(failing, Err("failed at 3".to_string()));
        }
        assert_eq!(in_parallel(0, 2, Ok::<usize, ()>), Ok(vec![]));
    }
}
