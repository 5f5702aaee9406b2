//! A mutation fuzzer for every reader, in process, on stable Rust.
//!
//!     cargo run --release --example fuzz -- [TARGET|all] [--runs N] [--seconds S] [--seed K]
//!
//! Why this and not cargo-fuzz or cargo-afl: cargo-fuzz needs nightly, and AFL++ here would
//! need its compiler wrappers installed from Debian and a process per input; the readers are
//! plain functions, so a loop that mutates the seeds (`lamina::fuzz::TARGETS`) and calls them
//! runs tens of thousands of inputs a second without either, deterministically from `--seed`.
//! What it has no equivalent of is coverage feedback: the mutations are chosen to reach the
//! failure kinds found so far (numbers made huge, tiny, negative or non-finite; lines repeated;
//! sizes in headers; bytes flipped, cut and spliced).
//!
//! Each input is written to a file in a temporary folder (the readers take paths, as the
//! commands do) and read inside `catch_unwind`. A failure stops the run and keeps the input in
//! `fuzz/crashes/TARGET/` (check it in; `tests/fuzz_replay.rs` replays the folder):
//! - a panic;
//! - a run over 2 s of CPU time (all threads; read from /proc, so a loaded machine does not
//!   count against the input), or over 120 s of wall time less the time its threads waited for
//!   a core (a run blocked without working; a run starved by other work on the machine is
//!   not one): a watchdog thread copies the input and exits with status 3;
//! - more than 1 GiB live at once, or one request over it (the global allocator refuses it,
//!   and the input, written before the call, is left at the path printed at the start).

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use lamina::fuzz::{seed_files, Target, TARGETS};

const LIVE_LIMIT: usize = 1 << 30;
/// CPU time one run may take (all threads).
const TIME_LIMIT: Duration = Duration::from_secs(2);
/// Wall time one run may take: only a run that waits instead of working gets near it. At 20 s,
/// two campaigns at `nice 19` stopped on inputs that had used 0.85 and 1.1 s of CPU (one is
/// refused in a millisecond when read alone) while release builds and a 2 GB benchmark held the
/// machine: blocked on the machine (disk writeback, memory), which the scheduler's wait does
/// not count, not on the input. A run that truly hangs without working still stops here.
const WALL_LIMIT: Duration = Duration::from_secs(120);
const MAX_INPUT: usize = 1 << 20;

/// The system allocator with a ceiling on live bytes.
struct Capped;

static LIVE: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size() > LIVE_LIMIT {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && LIVE.load(Ordering::Relaxed) + (new_size - old) > LIVE_LIMIT {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size > old {
                LIVE.fetch_add(new_size - old, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(old - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOC: Capped = Capped;

/// xorshift64*: small, fast, and the same everywhere.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that broke readers before: huge, tiny, negative, non-finite, 32-bit edges.
const TOKENS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-300",
    "-0",
    "0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "4294967295",
    "2147483648",
    "65535",
    "1e12",
    "999999999",
    "0.000000",
    "-0.000000",
    "1e6",
];

/// One mutation of `input`, kept under `MAX_INPUT` bytes.
fn mutate(input: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut v = input.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let len = v.len().max(1);
        match rng.below(9) {
            // A number-like run replaced by an extreme value.
            0 | 1 => {
                let starts: Vec<usize> = (0..v.len())
                    .filter(|&i| {
                        v[i].is_ascii_digit() && (i == 0 || !v[i - 1].is_ascii_alphanumeric())
                    })
                    .collect();
                if let Some(&s) = starts.get(rng.below(starts.len())) {
                    let mut e = s;
                    while e < v.len() && (v[e].is_ascii_digit() || b".eE+-".contains(&v[e])) {
                        e += 1;
                    }
                    let token = TOKENS[rng.below(TOKENS.len())].as_bytes();
                    v.splice(s..e, token.iter().copied());
                }
            }
            2 => {
                if !v.is_empty() {
                    let i = rng.below(v.len());
                    v[i] ^= 1 << rng.below(8);
                }
            }
            3 => {
                if !v.is_empty() {
                    let i = rng.below(v.len());
                    v[i] = [0u8, 0xff, b'-', b'.', b'e', b'9', b'\n', b'\\', b' '][rng.below(9)];
                }
            }
            4 => {
                let a = rng.below(len);
                let b = (a + rng.below(64)).min(v.len());
                v.drain(a.min(v.len())..b);
            }
            5 => {
                // A line repeated (many entities, faces, rules).
                let lines: Vec<&[u8]> = v.split(|&b| b == b'\n').collect();
                if !lines.is_empty() {
                    let k = rng.below(lines.len());
                    let times = [2, 10, 100, 1000][rng.below(4)];
                    let mut out = Vec::with_capacity(v.len());
                    for (i, l) in lines.iter().enumerate() {
                        let n = if i == k { times } else { 1 };
                        for _ in 0..n {
                            out.extend_from_slice(l);
                            out.push(b'\n');
                        }
                    }
                    v = out;
                }
            }
            6 => {
                let cut = rng.below(len);
                v.truncate(cut);
            }
            7 => {
                let i = rng.below(len).min(v.len());
                let token = TOKENS[rng.below(TOKENS.len())].as_bytes();
                v.splice(i..i, token.iter().copied());
            }
            _ => {
                // A chunk copied elsewhere.
                if v.len() > 2 {
                    let a = rng.below(v.len());
                    let b = (a + 1 + rng.below(256)).min(v.len());
                    let chunk = v[a..b].to_vec();
                    let at = rng.below(v.len());
                    v.splice(at..at, chunk);
                }
            }
        }
        v.truncate(MAX_INPUT);
    }
    v
}

struct Args {
    targets: Vec<&'static Target>,
    runs: u64,
    seconds: f64,
    seed: u64,
}

fn args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let mut out = Args {
        targets: TARGETS.iter().collect(),
        runs: u64::MAX,
        seconds: 60.0,
        seed: 1,
    };
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--runs" => out.runs = value("--runs")?.parse().map_err(|_| "--runs: a count")?,
            "--seconds" => {
                out.seconds = value("--seconds")?
                    .parse()
                    .map_err(|_| "--seconds: a number")?
            }
            "--seed" => out.seed = value("--seed")?.parse().map_err(|_| "--seed: a number")?,
            "all" => {}
            name => {
                out.targets = TARGETS.iter().filter(|t| t.name == name).collect();
                if out.targets.is_empty() {
                    let names: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
                    return Err(format!(
                        "no target `{name}` (targets: {})",
                        names.join(", ")
                    ));
                }
            }
        }
    }
    Ok(out)
}

/// CPU time this process has used, all threads, user and system, in milliseconds (fields 14
/// and 15 of /proc/self/stat, in ticks of 1/100 s); 0 where there is no /proc.
fn cpu_millis() -> u64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0;
    };
    // The fields after the command name, which is in parentheses and may hold spaces; the
    // first of them is field 3.
    let Some(rest) = stat.rfind(')').and_then(|i| stat.get(i + 2..)) else {
        return 0;
    };
    let fields: Vec<&str> = rest.split(' ').collect();
    let tick = |k: usize| {
        fields
            .get(k)
            .and_then(|f| f.parse::<u64>().ok())
            .unwrap_or(0)
    };
    (tick(11) + tick(12)) * 10
}

/// Time this process's threads have spent ready to run but waiting for a core (the second
/// field of each /proc/self/task/*/schedstat, ns), in milliseconds; 0 where there is no /proc.
/// On a loaded machine a run waits without working: that wait is not held against it.
fn waited_millis() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    let ns: u64 = tasks
        .filter_map(|t| t.ok())
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .sum();
    ns / 1_000_000
}

fn keep(root: &Path, target: &Target, input: &[u8], why: &str) -> PathBuf {
    let dir = root.join("fuzz/crashes").join(target.name);
    let _ = std::fs::create_dir_all(&dir);
    let hash = input.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    });
    let path = dir.join(format!("{why}-{hash:016x}.{}", target.ext));
    let _ = std::fs::write(&path, input);
    path
}

fn main() {
    let args = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("fuzz: {e}");
            std::process::exit(2);
        }
    };
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let work = std::env::temp_dir().join(format!("lamina-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&work).expect("a temporary folder");
    // Caught panics are counted, not printed.
    std::panic::set_hook(Box::new(|_| {}));
    println!(
        "inputs are written to {} (after an abort, the last one is there)",
        work.display()
    );
    println!(
        "{:<14} {:>10} {:>8} {:>10} {:>9} {:>9}",
        "target", "runs", "seconds", "runs/s", "slowest", "CPU"
    );
    let started = Arc::new(AtomicU64::new(0));
    let started_cpu = Arc::new(AtomicU64::new(0));
    let started_wait = Arc::new(AtomicU64::new(0));
    let busy = Arc::new(AtomicBool::new(false));
    // Runs of the current target so far, for the line a stop prints.
    let done = Arc::new(AtomicU64::new(0));
    let current = Arc::new(std::sync::Mutex::new(PathBuf::new()));
    let clock = Instant::now();
    {
        let (started, started_cpu, started_wait, busy, current, root, done) = (
            started.clone(),
            started_cpu.clone(),
            started_wait.clone(),
            busy.clone(),
            current.clone(),
            root.clone(),
            done.clone(),
        );
        std::thread::spawn(move || loop {
            std::thread::sleep(Duration::from_millis(100));
            let t = started.load(Ordering::Relaxed);
            let cpu = cpu_millis().saturating_sub(started_cpu.load(Ordering::Relaxed));
            // Wall time less the time spent waiting for a core (which only a loaded machine
            // makes): what is left is time blocked without working.
            let wall = (clock.elapsed().as_millis() as u64)
                .saturating_sub(t)
                .saturating_sub(
                    waited_millis().saturating_sub(started_wait.load(Ordering::Relaxed)),
                );
            if busy.load(Ordering::Relaxed)
                && (cpu > TIME_LIMIT.as_millis() as u64 || wall > WALL_LIMIT.as_millis() as u64)
            {
                // The input file is named after its target (`dxf.dxf`): keep it where the
                // replay test finds it.
                let path = current.lock().map(|p| p.clone()).unwrap_or_default();
                let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
                let input = std::fs::read(&path).unwrap_or_default();
                match TARGETS.iter().find(|t| t.name == name) {
                    Some(target) => eprintln!(
                        "fuzz: {name}: after {} runs without a failure, an input ran {cpu} ms \
                         of CPU time, {wall} ms of wall time; kept as {}",
                        done.load(Ordering::Relaxed),
                        keep(&root, target, &input, "hang").display()
                    ),
                    None => eprintln!(
                        "fuzz: an input ran {cpu} ms of CPU time, {wall} ms of wall time; it is \
                         {}",
                        path.display()
                    ),
                }
                std::process::exit(3);
            }
        });
    }
    let mut failed = false;
    for target in &args.targets {
        let seeds: Vec<Vec<u8>> = seed_files(&root, target)
            .iter()
            .filter_map(|p| std::fs::read(p).ok())
            .collect();
        if seeds.is_empty() {
            eprintln!("fuzz: {}: no seeds", target.name);
            failed = true;
            continue;
        }
        let mut rng = Rng(args.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
        let path = work.join(format!("{}.{}", target.name, target.ext));
        *current.lock().expect("not poisoned") = path.clone();
        let begin = Instant::now();
        let (mut runs, mut slowest, mut slowest_cpu) = (0u64, Duration::ZERO, 0u64);
        done.store(0, Ordering::Relaxed);
        while runs < args.runs && begin.elapsed().as_secs_f64() < args.seconds {
            let seed = &seeds[rng.below(seeds.len())];
            let input = mutate(seed, &mut rng);
            if std::fs::write(&path, &input).is_err() {
                eprintln!("fuzz: cannot write {}", path.display());
                std::process::exit(2);
            }
            let cpu = cpu_millis();
            started_cpu.store(cpu, Ordering::Relaxed);
            started_wait.store(waited_millis(), Ordering::Relaxed);
            started.store(clock.elapsed().as_millis() as u64, Ordering::Relaxed);
            busy.store(true, Ordering::Relaxed);
            let t = Instant::now();
            let outcome = std::panic::catch_unwind(|| (target.run)(&path));
            let took = t.elapsed();
            busy.store(false, Ordering::Relaxed);
            slowest = slowest.max(took);
            slowest_cpu = slowest_cpu.max(cpu_millis().saturating_sub(cpu));
            runs += 1;
            done.store(runs, Ordering::Relaxed);
            if outcome.is_err() {
                let kept = keep(&root, target, &input, "panic");
                eprintln!(
                    "fuzz: {}: after {} runs without a failure, a panic; kept as {}",
                    target.name,
                    runs - 1,
                    kept.display()
                );
                failed = true;
                break;
            }
        }
        let secs = begin.elapsed().as_secs_f64();
        println!(
            "{:<14} {:>10} {:>8.1} {:>10.0} {:>7.3} s {:>7.2} s",
            target.name,
            runs,
            secs,
            runs as f64 / secs,
            slowest.as_secs_f64(),
            slowest_cpu as f64 / 1000.0
        );
    }
    let _ = std::fs::remove_dir_all(&work);
    std::process::exit(if failed { 1 } else { 0 });
}
