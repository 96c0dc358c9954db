//! `glowbrick stress --fuzz N`: N corrupted inputs through every loader a player's files reach (RON world,
//! scene recipe, thesis `.vx`, MagicaVoxel `.vox`, settings RON), each from a corpus of real files
//! (`corpus`) mutated a few times (`mutate`). Every input must give a valid world (or settings) or one error
//! line; a panic, a multi-line error, an input slower than `SLOW_INPUT` or one that makes the loader hold more
//! than `MAX_INPUT_HEAP` is a finding, saved to `fuzz-findings/` with the command that replays it.
//!
//! Inputs are numbered and input i of a target is a pure function of (seed, target, i), so a run is repeatable
//! on any number of threads and `--fuzz-only TARGET:I` replays one input. A watchdog ends the run (exit 1) when
//! one input runs longer than `HUNG_INPUT`, saving that input first.

pub mod corpus;
pub mod mutate;

use crate::alloc_watch::{HeapMark, is_installed};
use crate::progress::Progress;
use crate::reference::sampling::Pcg;
use crate::settings::RenderSettings;
use crate::world::VoxelWorld;
use crate::world::format::{parse_world, text_from_bytes};
use crate::world::grid::MAX_WORLD_EDGE;
use crate::world::import::{vox, vx};
use crate::world::recipe::parse_recipe;
use crate::world::region_save::EndlessSave;
use corpus::Seed;
use mutate::{Kind, mutate};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// An input slower than this is a finding (the largest valid corpus file loads in well under a second).
pub const SLOW_INPUT: Duration = Duration::from_secs(2);
/// An input still running after this ends the run: a hang.
pub const HUNG_INPUT: Duration = Duration::from_secs(60);
/// The most heap one input may make a loader hold at once. A 2048^3 world's brick index is 64 MiB; a file
/// that claims more than it holds must not get it.
pub const MAX_INPUT_HEAP: u64 = 512 << 20;

/// A loader the fuzzer drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    World,
    Recipe,
    Vx,
    Vox,
    Settings,
    /// An endless world's `world.ron`.
    Endless,
}

impl Target {
    pub const ALL: [Target; 6] =
        [Target::World, Target::Recipe, Target::Vx, Target::Vox, Target::Settings, Target::Endless];

    pub fn name(self) -> &'static str {
        match self {
            Target::World => "world",
            Target::Recipe => "recipe",
            Target::Vx => "vx",
            Target::Vox => "vox",
            Target::Settings => "settings",
            Target::Endless => "endless",
        }
    }

    pub fn from_name(name: &str) -> Result<Target, String> {
        Target::ALL.into_iter().find(|t| t.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
            format!("no fuzz target '{name}' (have: {})", names.join(", "))
        })
    }

    fn kind(self) -> Kind {
        match self {
            Target::Vx | Target::Vox => Kind::Binary,
            _ => Kind::Text,
        }
    }

    fn extension(self) -> &'static str {
        match self {
            Target::Vx => "vx",
            Target::Vox => "vox",
            _ => "ron",
        }
    }

    /// The input as the loader reads it from disk. A `.vx` seed is its decompressed payload: the mutations
    /// hit the header, counts and positions, and most inputs are compressed again (one in eight mutates the
    /// compressed bytes instead, for the gzip layer).
    fn file_bytes(self, mutated: Vec<u8>, rng: &mut Pcg) -> Vec<u8> {
        if self != Target::Vx || rng.next_u32().is_multiple_of(8) {
            return mutated;
        }
        corpus::gzip(&mutated)
    }

    /// Runs the loader on a file's bytes: a summary of what loaded, or its error.
    pub fn load(self, bytes: &[u8]) -> Result<String, String> {
        let location = format!("fuzz.{}", self.extension());
        let text = || text_from_bytes(bytes.to_vec(), &location).map_err(|e| e.to_string());
        let world = |w: VoxelWorld| {
            let size = w.grid.size();
            if size.max_element() > MAX_WORLD_EDGE {
                return Err(format!("BUG: a {size} world loaded, larger than {MAX_WORLD_EDGE} per axis"));
            }
            Ok(format!("a {}x{}x{} world", size.x, size.y, size.z))
        };
        match self {
            Target::World => world(parse_world(&text()?, &location).map_err(|e| e.to_string())?),
            Target::Recipe => world(parse_recipe(&text()?, &location).map_err(|e| e.to_string())?),
            Target::Vx => {
                let open = || Ok(flate2::read::GzDecoder::new(bytes));
                world(vx::read_vx(open, "fuzz", &location).map_err(|e| e.to_string())?)
            }
            Target::Vox => {
                let file = vox::parse_vox(bytes).map_err(|e| format!("{location}: {e}"))?;
                world(vox::vox_world(&file).map_err(|e| format!("{location}: {e}"))?)
            }
            Target::Settings => {
                RenderSettings::default().with_ron(&text()?, &location)?;
                Ok("settings".into())
            }
            Target::Endless => {
                let save = EndlessSave::parse(&text()?, Path::new("fuzz"), &location).map_err(|e| e.to_string())?;
                Ok(format!("the endless world of seed {}, {} high", save.seed, save.height))
            }
        }
    }
}

/// What a run does.
#[derive(Clone, Debug)]
pub struct FuzzConfig {
    /// Inputs over all targets (split evenly).
    pub inputs: u64,
    pub targets: Vec<Target>,
    pub seed: u64,
    pub threads: usize,
    /// Where findings are saved.
    pub findings_dir: PathBuf,
}

/// One input that broke a rule.
#[derive(Clone, Debug)]
pub struct Finding {
    pub target: Target,
    pub index: u64,
    pub what: String,
    pub saved: Option<PathBuf>,
}

/// What one target's inputs did.
#[derive(Clone, Debug)]
pub struct TargetReport {
    pub target: Target,
    pub seeds: Vec<String>,
    /// Corpus files left out, and why (too slow to load many times).
    pub left_out: Vec<String>,
    pub inputs: u64,
    pub loaded: u64,
    pub errors: u64,
    pub panics: u64,
    pub slowest: Duration,
    pub peak_heap: u64,
    pub seconds: f64,
}

/// A whole run.
#[derive(Clone, Debug)]
pub struct FuzzReport {
    pub targets: Vec<TargetReport>,
    pub findings: Vec<Finding>,
    pub heap_watched: bool,
    pub seed: u64,
}

impl FuzzReport {
    pub fn inputs(&self) -> u64 {
        self.targets.iter().map(|t| t.inputs).sum()
    }

    pub fn failure(&self) -> Option<String> {
        let first = self.findings.first()?;
        Some(format!(
            "{} findings; the first: {} input {}: {}",
            self.findings.len(),
            first.target.name(),
            first.index,
            first.what
        ))
    }
}

impl std::fmt::Display for FuzzReport {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        writeln!(
            f,
            "| target | seeds | inputs | loaded | one-line errors | panics | slowest input | peak heap of one input | time |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|")?;
        for t in &self.targets {
            let heap = if self.heap_watched {
                format!("{:.1} MiB", t.peak_heap as f64 / (1 << 20) as f64)
            } else {
                "not watched".into()
            };
            writeln!(
                f,
                "| {} | {} | {} | {} | {} | {} | {:.0} ms | {heap} | {:.0} s |",
                t.target.name(),
                t.seeds.len(),
                t.inputs,
                t.loaded,
                t.errors,
                t.panics,
                t.slowest.as_secs_f64() * 1e3,
                t.seconds
            )?;
        }
        for t in &self.targets {
            writeln!(f, "{} seeds: {}", t.target.name(), t.seeds.join(", "))?;
            if !t.left_out.is_empty() {
                writeln!(f, "{} left out: {}", t.target.name(), t.left_out.join("; "))?;
            }
        }
        for finding in &self.findings {
            let saved = finding.saved.as_ref().map(|p| format!(" (saved: {})", p.display())).unwrap_or_default();
            writeln!(f, "FINDING {} input {}: {}{saved}", finding.target.name(), finding.index, finding.what)?;
        }
        write!(
            f,
            "{} inputs (seed {}), {} findings; replay one with `glowbrick stress --fuzz-only TARGET:INDEX --seed {}`",
            self.inputs(),
            self.seed,
            self.findings.len(),
            self.seed
        )
    }
}

/// Input `index` of `target`'s run: a mutated seed, as the loader would read it from disk.
pub fn input(seeds: &[Seed], target: Target, seed: u64, index: u64) -> Vec<u8> {
    let stream = ((Target::ALL.iter().position(|&t| t == target).unwrap_or(0) as u64) << 48) | index;
    let mut rng = Pcg::new(seed, stream);
    let base = &seeds[rng.next_u32() as usize % seeds.len()];
    let donor = &seeds[rng.next_u32() as usize % seeds.len()];
    let mutated = mutate(&base.bytes, &donor.bytes, target.kind(), &mut rng);
    target.file_bytes(mutated, &mut rng)
}

/// What a loader did with one input: its answer (Ok: loaded, Err: its error), or the panic it raised.
type Outcome = Result<Result<String, String>, String>;

/// Runs one input, catching a panic: the loader's answer, or the panic's message.
fn run_one(target: Target, bytes: &[u8]) -> Outcome {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| target.load(bytes))).map_err(|panic| {
        panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "unknown panic".into())
    })
}

/// What a loader's answer breaks, if anything.
fn judge(outcome: &Outcome, took: Duration, heap: u64) -> Option<String> {
    match outcome {
        Err(panic) => return Some(format!("panic: {}", panic.replace('\n', " "))),
        Ok(Ok(summary)) if summary.starts_with("BUG") => return Some(summary.clone()),
        Ok(Err(line)) if line.is_empty() || line.contains('\n') => {
            return Some(format!("the error is not one line: {line:?}"));
        }
        _ => {}
    }
    if took > SLOW_INPUT {
        return Some(format!("took {:.1} s (limit {} s)", took.as_secs_f64(), SLOW_INPUT.as_secs()));
    }
    (heap > MAX_INPUT_HEAP).then(|| format!("held {} MiB of heap (limit {} MiB)", heap >> 20, MAX_INPUT_HEAP >> 20))
}

fn save_finding(dir: &Path, target: Target, index: u64, bytes: &[u8]) -> Option<PathBuf> {
    std::fs::create_dir_all(dir).ok()?;
    let path = dir.join(format!("{}-{index}.{}", target.name(), target.extension()));
    std::fs::write(&path, bytes).ok().map(|_| path)
}

/// One worker's view of the input it is on, for the watchdog.
struct Busy {
    /// Milliseconds since the run started when the current input began; 0 when idle.
    since_ms: AtomicU64,
    index: AtomicU64,
}

/// Runs every target's share of the inputs and reports.
pub fn run_fuzz(config: &FuzzConfig) -> Result<FuzzReport, String> {
    if config.targets.is_empty() || config.inputs == 0 || config.threads == 0 {
        return Err("the fuzzer needs a target, inputs and a thread".into());
    }
    let per_target = config.inputs.div_ceil(config.targets.len() as u64);
    let previous_hook = std::panic::take_hook();
    // Panics are findings, reported with their message; the default hook would print each one's backtrace.
    std::panic::set_hook(Box::new(|_| {}));
    let mut report =
        FuzzReport { targets: Vec::new(), findings: Vec::new(), heap_watched: is_installed(), seed: config.seed };
    let result = config.targets.iter().try_for_each(|&target| {
        let (target_report, findings) = run_target(config, target, per_target)?;
        report.targets.push(target_report);
        report.findings.extend(findings);
        Ok::<(), String>(())
    });
    std::panic::set_hook(previous_hook);
    result.map(|()| report)
}

/// What one target's inputs did, summed over the threads.
#[derive(Clone, Copy, Default)]
struct Totals {
    loaded: u64,
    errors: u64,
    panics: u64,
    slowest: Duration,
    peak_heap: u64,
}

impl Totals {
    fn count(&mut self, outcome: &Outcome, took: Duration, heap: u64) {
        match outcome {
            Ok(Ok(_)) => self.loaded += 1,
            Ok(Err(_)) => self.errors += 1,
            Err(_) => self.panics += 1,
        }
        self.slowest = self.slowest.max(took);
        self.peak_heap = self.peak_heap.max(heap);
    }

    fn merge(&mut self, other: Totals) {
        self.loaded += other.loaded;
        self.errors += other.errors;
        self.panics += other.panics;
        self.slowest = self.slowest.max(other.slowest);
        self.peak_heap = self.peak_heap.max(other.peak_heap);
    }
}

/// What every fuzzing thread of one target shares.
struct FuzzRun<'a> {
    config: &'a FuzzConfig,
    target: Target,
    inputs: u64,
    seeds: &'a [Seed],
    start: Instant,
    progress: Progress,
    busy: Vec<Busy>,
    findings: Mutex<Vec<Finding>>,
    totals: Mutex<Totals>,
    finished: AtomicBool,
}

impl FuzzRun<'_> {
    /// The watchdog: an input that never returns cannot be caught, so save it and end the run.
    fn watch_for_hangs(&self) {
        while !self.finished.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(200));
            let now = self.start.elapsed().as_millis() as u64;
            for b in self.busy.iter() {
                let since = b.since_ms.load(Ordering::Relaxed);
                if since > 0 && now.saturating_sub(since) > HUNG_INPUT.as_millis() as u64 {
                    let index = b.index.load(Ordering::Relaxed);
                    let bytes = input(self.seeds, self.target, self.config.seed, index);
                    let saved = save_finding(&self.config.findings_dir, self.target, index, &bytes);
                    eprintln!(
                        "error: fuzz {} input {index} still running after {} s: a hang (saved: {:?})",
                        self.target.name(),
                        HUNG_INPUT.as_secs(),
                        saved
                    );
                    std::process::exit(1);
                }
            }
        }
    }

    /// Thread `t`'s share of the inputs: every `threads`-th from `t`.
    fn fuzz_share(&self, t: usize) {
        let (target, busy) = (self.target, &self.busy[t]);
        let mut mine = Totals::default();
        let mut done = 0u64;
        for index in (t as u64..self.inputs).step_by(self.config.threads) {
            let bytes = input(self.seeds, target, self.config.seed, index);
            busy.index.store(index, Ordering::Relaxed);
            busy.since_ms.store(self.start.elapsed().as_millis() as u64 + 1, Ordering::Relaxed);
            let mark = HeapMark::now();
            let began = Instant::now();
            let outcome = run_one(target, &bytes);
            let took = began.elapsed();
            let heap = mark.peak_bytes();
            busy.since_ms.store(0, Ordering::Relaxed);
            mine.count(&outcome, took, heap);
            if let Some(what) = judge(&outcome, took, heap) {
                let saved = save_finding(&self.config.findings_dir, target, index, &bytes);
                self.progress.println(&format!("FINDING {} input {index}: {what}", target.name()));
                if let Ok(mut list) = self.findings.lock() {
                    list.push(Finding { target, index, what, saved });
                }
            }
            done += 1;
            if done.is_multiple_of(64) {
                self.progress.advance(64);
            }
        }
        self.progress.advance(done % 64);
        if let Ok(mut all) = self.totals.lock() {
            all.merge(mine);
        }
    }
}

fn run_target(config: &FuzzConfig, target: Target, inputs: u64) -> Result<(TargetReport, Vec<Finding>), String> {
    let (seeds, left_out) = corpus::seeds(target)?;
    let run = FuzzRun {
        config,
        target,
        inputs,
        seeds: &seeds,
        start: Instant::now(),
        progress: Progress::new(&format!("fuzz {}", target.name()), inputs),
        busy: (0..config.threads).map(|_| Busy { since_ms: AtomicU64::new(0), index: AtomicU64::new(0) }).collect(),
        findings: Mutex::new(Vec::new()),
        totals: Mutex::new(Totals::default()),
        finished: AtomicBool::new(false),
    };
    std::thread::scope(|scope| {
        scope.spawn(|| run.watch_for_hangs());
        let run = &run;
        let workers: Vec<_> = (0..config.threads).map(|t| scope.spawn(move || run.fuzz_share(t))).collect();
        for worker in workers {
            let _ = worker.join();
        }
        run.finished.store(true, Ordering::Relaxed);
    });
    run.progress.finish();
    let totals = *run.totals.lock().map_err(|_| "fuzz totals poisoned")?;
    let mut findings = run.findings.into_inner().map_err(|_| "fuzz findings poisoned")?;
    findings.sort_by_key(|f| f.index);
    let report = TargetReport {
        target,
        seeds: seeds.iter().map(|s| s.name.clone()).collect(),
        left_out,
        inputs,
        loaded: totals.loaded,
        errors: totals.errors,
        panics: totals.panics,
        slowest: totals.slowest,
        peak_heap: totals.peak_heap,
        seconds: run.start.elapsed().as_secs_f64(),
    };
    Ok((report, findings))
}

/// Replays input `index` of `target`: the loader's answer, or what the input breaks.
pub fn replay(target: Target, seed: u64, index: u64, save_to: Option<&Path>) -> Result<String, String> {
    let (seeds, _) = corpus::seeds(target)?;
    let bytes = input(&seeds, target, seed, index);
    if let Some(path) = save_to {
        std::fs::write(path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let mark = HeapMark::now();
    let began = Instant::now();
    let outcome = run_one(target, &bytes);
    let (took, heap) = (began.elapsed(), mark.peak_bytes());
    let answer = match &outcome {
        Ok(Ok(summary)) => format!("loaded: {summary}"),
        Ok(Err(line)) => format!("error: {line}"),
        Err(panic) => format!("panic: {panic}"),
    };
    match judge(&outcome, took, heap) {
        Some(what) => Err(format!("{} input {index}: {what} ({answer})", target.name())),
        None => {
            Ok(format!("{answer} ({:.1} ms, {:.1} MiB heap)", took.as_secs_f64() * 1e3, heap as f64 / (1 << 20) as f64))
        }
    }
}
