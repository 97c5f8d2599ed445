//! Independent pieces of work on several threads, with the results (and the error) a loop
//! in order on one thread would give.
//!
//! The threads are kept between calls, one set per thread count ([`pool`]): a thread
//! spawned for each call can start late. On the 2-core machine the benchmarks run on, a
//! freshly spawned thread was queued behind the thread that spawned it until that one
//! blocked (the spawner working beside it for 1 ms: the two finished after 2 ms, one after
//! the other), while a parked worker woke in ≈ 40 µs. So work that overlaps with the
//! caller's own ([`side_by_side`]) needs threads that already exist.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

/// The thread count `threads` asks for: 0 is as many as the machine has.
pub fn thread_count(threads: usize) -> usize {
    match threads {
        0 => machine_threads(),
        n => n,
    }
}

/// The machine's threads, read once per process: the standard library reads them from the
/// system (cgroup files on Linux) at every call, which took a few percent of a sensitivity
/// request that asked at each of its parallel calls.
fn machine_threads() -> usize {
    static MACHINE_THREADS: OnceLock<usize> = OnceLock::new();
    *MACHINE_THREADS.get_or_init(|| std::thread::available_parallelism().map_or(1, usize::from))
}

/// The kept workers of one process: its id, and one set per thread count asked for.
struct Pools {
    process: u32,
    sets: Vec<(usize, Arc<rayon::ThreadPool>)>,
}

/// The worker threads of `threads` threads (made on first use, then kept for the process's
/// life: one set per thread count asked for). `None` if the system will not start them,
/// in which case the work runs in order on the calling thread (the numbers are the same).
fn pool(threads: usize) -> Option<Arc<rayon::ThreadPool>> {
    static POOLS: Mutex<Pools> = Mutex::new(Pools {
        process: 0,
        sets: Vec::new(),
    });
    // a panic while the lock was held left the list as it was (a push is the only change)
    let mut pools = POOLS.lock().unwrap_or_else(PoisonError::into_inner);
    // a process forked from one that had workers (Python's multiprocessing, for one) has
    // their handles but not their threads: work handed to them would wait forever. Its
    // own are made anew; the parent's are left alone (dropping them would signal threads
    // that do not exist here)
    let process = std::process::id();
    if pools.process != process {
        for set in std::mem::take(&mut pools.sets) {
            std::mem::forget(set);
        }
        pools.process = process;
    }
    if let Some((_, pool)) = pools.sets.iter().find(|(n, _)| *n == threads) {
        return Some(pool.clone());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|k| format!("pendkit-worker-{k}"))
        .build()
        .ok()?;
    let pool = Arc::new(pool);
    pools.sets.push((threads, pool.clone()));
    Some(pool)
}

/// The kept workers for `threads` (0: as many as the machine has) when that is more than
/// one thread and they can be started. At most [`MAX_THREADS_PER_CORE`] times the machine's
/// threads are made (the work is arithmetic: more would only wait their turn), so that a
/// huge count asked for costs no more than that.
fn workers(threads: usize) -> Option<(usize, Arc<rayon::ThreadPool>)> {
    if threads == 1 {
        return None;
    }
    let most = MAX_THREADS_PER_CORE * thread_count(0).max(1);
    let threads = thread_count(threads).min(most);
    if threads < 2 {
        return None;
    }
    pool(threads).map(|pool| (threads, pool))
}

/// How many kept threads per thread of the machine [`in_parallel`] makes at most.
pub const MAX_THREADS_PER_CORE: usize = 4;

/// `work(j)` for every j in 0..n on up to `threads` threads (0: as many as the machine
/// has), the results in j order. Each j is computed exactly as on one thread (the numbers
/// do not depend on the thread count); on errors the one of the smallest j is returned, as
/// a loop in order would, and no j after it is started. May be called from inside other
/// parallel work (the workers then share it).
pub fn in_parallel<T: Send, E: Send>(
    n: usize,
    threads: usize,
    work: impl Fn(usize) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E> {
    in_parallel_with(n, threads, || (), |_, j| work(j))
}

/// [`in_parallel`] with a scratch value per thread: `work(scratch, j)`, each thread's
/// scratch made by `scratch()` and handed to every j that thread computes (for what one
/// piece can reuse from the one before; the results must not depend on it).
pub fn in_parallel_with<W, T: Send, E: Send>(
    n: usize,
    threads: usize,
    scratch: impl Fn() -> W + Sync,
    work: impl Fn(&mut W, usize) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E> {
    let Some((threads, pool)) = workers(threads).filter(|_| n > 1) else {
        let mut mine = scratch();
        return (0..n).map(|j| work(&mut mine, j)).collect();
    };
    let next = AtomicUsize::new(0);
    let first_error = AtomicUsize::new(usize::MAX);
    // grown as the pieces finish, not reserved for `n` up front (any `n` is a valid count)
    let finished: Mutex<Vec<(usize, Result<T, E>)>> = Mutex::new(Vec::new());
    // each worker takes the next j until none is left: the pieces' costs may differ widely
    pool.scope(|scope| {
        for _ in 0..threads.min(n) {
            scope.spawn(|_| {
                let mut mine = scratch();
                let mut done = Vec::new();
                loop {
                    let j = next.fetch_add(1, Ordering::Relaxed);
                    if j >= n || j > first_error.load(Ordering::Relaxed) {
                        break;
                    }
                    let result = work(&mut mine, j);
                    if result.is_err() {
                        first_error.fetch_min(j, Ordering::Relaxed);
                    }
                    done.push((j, result));
                }
                // a panic in another worker is carried on by the scope; the results
                // pushed before it are whole
                finished
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .extend(done);
            });
        }
    });
    let mut finished = finished
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner);
    finished.sort_unstable_by_key(|(j, _)| *j);
    let mut mine = scratch();
    let mut out = Vec::with_capacity(finished.len());
    let mut pieces = finished.into_iter().peekable();
    for j in 0..n {
        match pieces.next_if(|(k, _)| *k == j) {
            Some((_, result)) => out.push(result?),
            // not started, which only follows an error of a smaller j (returned above);
            // done here rather than assumed
            None => out.push(work(&mut mine, j)?),
        }
    }
    Ok(out)
}

/// `a()` and `b()`, side by side on two of the kept workers when `threads` (0: as many as
/// the machine has) is more than one, else one after the other on the calling thread. Each
/// may use [`in_parallel`] with the same `threads`: the workers share that work.
pub fn side_by_side<A: Send, B: Send>(
    threads: usize,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    match workers(threads) {
        Some((_, pool)) => pool.join(a, b),
        None => (a(), b()),
    }
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
        // a huge thread count is capped, not made
        let squares = in_parallel(5, usize::MAX, |j| Ok::<_, ()>(j * j));
        assert_eq!(squares, Ok(vec![0, 1, 4, 9, 16]));
    }

    #[test]
    fn work_nested_in_side_by_side_gives_what_one_thread_gives() {
        for threads in [1, 2, 3] {
            let (sums, product) = side_by_side(
                threads,
                || in_parallel(5, threads, |j| Ok::<_, ()>((0..=j).sum::<usize>())),
                || in_parallel(4, threads, |j| Ok::<_, ()>(j + 1)).map(|v| v.iter().product()),
            );
            assert_eq!(sums, Ok(vec![0, 1, 3, 6, 10]));
            assert_eq!(product, Ok::<usize, ()>(24));
        }
    }

    #[test]
    fn each_thread_keeps_its_scratch_between_pieces() {
        for threads in [1, 2, 3] {
            // the scratch counts the pieces its thread computed: every piece sees a count
            // of at least 1, and the counts of all threads together are the pieces
            let seen = in_parallel_with(
                10,
                threads,
                || 0usize,
                |count, j| {
                    *count += 1;
                    Ok::<_, ()>((j, *count))
                },
            )
            .unwrap_or_default();
            assert_eq!(
                seen.iter().map(|&(j, _)| j).collect::<Vec<_>>(),
                (0..10).collect::<Vec<_>>()
            );
            assert!(seen.iter().all(|&(_, count)| count >= 1));
            if threads == 1 {
                assert_eq!(
                    seen.iter().map(|&(_, c)| c).collect::<Vec<_>>(),
                    (1..=10).collect::<Vec<_>>()
                );
            }
        }
    }

    #[test]
    fn a_panic_in_the_work_reaches_the_caller() {
        let caught = std::panic::catch_unwind(|| {
            in_parallel(6, 2, |j| {
                assert!(j != 4, "piece 4");
                Ok::<_, ()>(j)
            })
        });
        assert!(caught.is_err());
    }
}
