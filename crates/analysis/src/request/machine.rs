//! What a request may ask of this machine: worker threads (every core by default, at
//! most [`THREADS_PER_CORE`] per core) and memory, whose budget is the least of the memory
//! the kernel says is available (or the caller's `max_memory`) and the limits the kernel
//! sets this process (`ulimit -v` less what it maps, `ulimit -d`, its cgroups' v2
//! `memory.max` or v1 `memory.limit_in_bytes` less their use, up the hierarchy: Slurm and
//! Kubernetes put jobs in cgroups). A request whose [`MemoryNeed`] exceeds the budget is
//! refused before it starts ([`pool_for`]).

use std::path::{Path, PathBuf};

use rvtol_deviation::human_bytes;

use super::input_file::{read_text, ReadLimit};
use super::memory::MemoryNeed;
use super::{Caller, Refusal};

/// Most worker threads per core: more only adds scheduling and per-thread buffers (the
/// run time grew about quadratically with the thread count beyond it).
pub const THREADS_PER_CORE: u64 = 4;

/// Cores of this machine (1 when it cannot tell).
pub fn cores() -> u64 {
    std::thread::available_parallelism().map_or(1, |n| n.get() as u64)
}

/// The worker-thread count to use: the one asked for (at least 1, at most
/// [`THREADS_PER_CORE`] per core) or every core.
pub fn threads(asked: Option<u64>, caller: Caller) -> Result<usize, Refusal> {
    let cores = cores();
    let most = THREADS_PER_CORE * cores;
    match asked {
        None => Ok(cores as usize),
        Some(0) => Err(Refusal::option(caller, "threads", "must be at least 1")),
        Some(n) if n <= most => Ok(n as usize),
        Some(n) => Err(Refusal::option(
            caller,
            "threads",
            format!(
                "{n} is more than {most} ({THREADS_PER_CORE} per core on this machine's {cores} cores); more threads than cores only slow the run down"
            ),
        )),
    }
}

/// A rayon pool of `threads` workers; the error is one line.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|err| format!("cannot start {threads} worker threads: {err}"))
}

/// The pool of a request of `command` whose memory need at its thread count (`need`) fits
/// the budget ([`memory_budget`]): the threads asked for, or every core.
pub fn pool_for(
    command: &str,
    asked_threads: Option<u64>,
    max_memory: Option<f64>,
    caller: Caller,
    need: impl FnOnce(usize) -> MemoryNeed,
) -> Result<rayon::ThreadPool, String> {
    let threads = threads(asked_threads, caller).map_err(|refusal| refusal.to_string())?;
    check_memory(need(threads), command, max_memory, threads, caller)?;
    thread_pool(threads)
}

/// Refuses a request of `command` whose memory need exceeds the budget, with one line
/// (`threads` worker threads each reserve address space).
pub fn check_memory(
    need: MemoryNeed,
    command: &str,
    max_memory: Option<f64>,
    threads: usize,
    caller: Caller,
) -> Result<(), String> {
    let (budget, source) = memory_budget(max_memory, threads, caller);
    need.check(budget, &source, caller)
        .map_err(|message| format!("{command}: {message}"))
}

/// Address space a worker thread reserves beyond what the process maps when the budget is
/// worked out: glibc's malloc arena of the thread (64 MiB reserved) and its stack (2 MiB),
/// rounded up.
const ADDRESS_SPACE_PER_THREAD: f64 = 72.0 * 1024.0 * 1024.0;

/// Limits at or above this many bytes mean none (cgroup v1 writes 2⁶³ − 4096 for none).
const NO_LIMIT: f64 = 4.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0;

/// One limit on the memory this process may still take: the bytes left under it and what
/// it is, in words, for the message that names it.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryLimit {
    /// Bytes left under the limit (0 when it is already reached).
    pub bytes: f64,
    /// What the limit is and how it was worked out.
    pub what: String,
}

/// The soft limit of the resource `name` (`Max address space`, `Max data size`) in the
/// text of /proc/self/limits, in bytes; `None` when unlimited or absent.
pub fn soft_limit_of(limits_text: &str, name: &str) -> Option<f64> {
    let rest = limits_text
        .lines()
        .find_map(|line| line.strip_prefix(name))?;
    let soft = rest.split_whitespace().next()?;
    soft.parse::<f64>().ok().filter(|&bytes| bytes < NO_LIMIT)
}

/// A `Key:   1234 kB` figure of /proc/self/status or /proc/meminfo, in bytes.
pub fn kilobytes_field(text: &str, key: &str) -> Option<f64> {
    text.lines()
        .find_map(|line| line.strip_prefix(key)?.strip_prefix(':'))
        .and_then(|rest| {
            rest.trim()
                .trim_end_matches("kB")
                .trim()
                .parse::<f64>()
                .ok()
        })
        .map(|kib| kib * 1024.0)
}

/// A number of a cgroup file (`memory.max`, `memory.limit_in_bytes`): `None` for `max`,
/// a limit that means none, or text that is no number.
fn cgroup_number(text: &str) -> Option<f64> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|&bytes| bytes < NO_LIMIT)
}

/// A `key value` line of a cgroup's memory.stat.
fn stat_field(text: &str, key: &str) -> Option<f64> {
    text.lines().find_map(|line| {
        let (name, value) = line.split_once(' ')?;
        (name == key).then(|| value.trim().parse::<f64>().ok())?
    })
}

/// The version of a cgroup hierarchy: v2 (unified) or v1's memory controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CgroupVersion {
    /// cgroup v2: `memory.max`, `memory.current`, `inactive_file` of memory.stat.
    Unified,
    /// cgroup v1's memory controller: `memory.limit_in_bytes`, `memory.usage_in_bytes`,
    /// `total_inactive_file` of memory.stat.
    MemoryController,
}

/// The folders of this process's memory cgroups, from the texts of /proc/self/cgroup and
/// /proc/self/mountinfo: for each hierarchy that has a memory limit (v2, and v1's memory
/// controller), the cgroup's folder and the hierarchy's mount point, where the walk up
/// its ancestors stops.
pub fn memory_cgroup_folders(
    cgroup_text: &str,
    mountinfo_text: &str,
) -> Vec<(CgroupVersion, PathBuf, PathBuf)> {
    let mut found = Vec::new();
    for line in cgroup_text.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(cgroup)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let version = if controllers.is_empty() {
            CgroupVersion::Unified
        } else if controllers.split(',').any(|c| c == "memory") {
            CgroupVersion::MemoryController
        } else {
            continue;
        };
        // mountinfo: id parent major:minor root mount-point options [optional…] - type
        // source super-options.
        let mount = mountinfo_text.lines().find_map(|mount| {
            let (before, after) = mount.split_once(" - ")?;
            let mut after = after.split_whitespace();
            let fstype = after.next()?;
            let super_options = after.nth(1).unwrap_or("");
            let wanted = match version {
                CgroupVersion::Unified => fstype == "cgroup2",
                CgroupVersion::MemoryController => {
                    fstype == "cgroup" && super_options.split(',').any(|o| o == "memory")
                }
            };
            if !wanted {
                return None;
            }
            let mut before = before.split_whitespace();
            let root = before.nth(3)?;
            let point = before.next()?;
            Some((root.to_string(), unescape_mount_path(point)))
        });
        let Some((root, point)) = mount else {
            continue;
        };
        let point = PathBuf::from(point);
        // The cgroup's path is relative to the hierarchy's root; a mount of a sub-tree (a
        // container's) shows the part below its root.
        let below = if root == "/" {
            Some(cgroup)
        } else {
            cgroup
                .strip_prefix(root.as_str())
                .filter(|rest| rest.is_empty() || rest.starts_with('/'))
        };
        let folder = match below {
            Some(rest) => point.join(rest.trim_start_matches('/')),
            None => point.clone(),
        };
        found.push((version, folder, point));
    }
    found
}

/// A path of /proc/self/mountinfo with its octal escapes (`\040` for a space) undone.
fn unescape_mount_path(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let code = bytes
            .get(i + 1..i + 4)
            .and_then(|digits| std::str::from_utf8(digits).ok())
            .and_then(|digits| u8::from_str_radix(digits, 8).ok());
        if let (b'\\', Some(value)) = (bytes[i], code) {
            out.push(value);
            i += 4;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The tightest memory limit of a cgroup and its ancestors up to the hierarchy's mount
/// point: each level's limit less its use (less the inactive file cache, which the kernel
/// reclaims before it runs out). `read` gives a file's text.
pub fn cgroup_limit(
    version: CgroupVersion,
    folder: &Path,
    mount_point: &Path,
    read: &dyn Fn(&Path) -> Option<String>,
) -> Option<MemoryLimit> {
    let (limit_file, usage_file, inactive_key) = match version {
        CgroupVersion::Unified => ("memory.max", "memory.current", "inactive_file"),
        CgroupVersion::MemoryController => (
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file",
        ),
    };
    let mut tightest: Option<MemoryLimit> = None;
    let mut level = Some(folder);
    while let Some(dir) = level {
        let limit_path = dir.join(limit_file);
        if let Some(limit) = read(&limit_path).as_deref().and_then(cgroup_number) {
            let used = read(&dir.join(usage_file))
                .as_deref()
                .and_then(cgroup_number)
                .unwrap_or(0.0);
            let reclaimable = read(&dir.join("memory.stat"))
                .as_deref()
                .and_then(|stat| stat_field(stat, inactive_key))
                .unwrap_or(0.0);
            let in_use = (used - reclaimable).max(0.0);
            let left = (limit - in_use).max(0.0);
            if tightest.as_ref().is_none_or(|t| left < t.bytes) {
                tightest = Some(MemoryLimit {
                    bytes: left,
                    what: format!(
                        "the memory limit of this process's cgroup, {} {} less {} in use",
                        limit_path.display(),
                        human_bytes(limit),
                        human_bytes(in_use)
                    ),
                });
            }
        }
        if dir == mount_point {
            break;
        }
        level = dir
            .parent()
            .filter(|parent| parent.starts_with(mount_point));
    }
    tightest
}

/// The limits the kernel sets this process, from the texts of its files: the address
/// space (`ulimit -v`, less what the process maps already and what `threads` worker
/// threads will reserve), the data size (`ulimit -d`, less the data the process has) and
/// its cgroups' memory limits (Slurm and Kubernetes put jobs in cgroups).
pub fn process_limits(threads: usize, read: &dyn Fn(&Path) -> Option<String>) -> Vec<MemoryLimit> {
    let mut limits = Vec::new();
    let limits_text = read(Path::new("/proc/self/limits")).unwrap_or_default();
    let status = read(Path::new("/proc/self/status")).unwrap_or_default();
    if let Some(limit) = soft_limit_of(&limits_text, "Max address space") {
        let mapped = kilobytes_field(&status, "VmSize").unwrap_or(0.0);
        let reserved = threads as f64 * ADDRESS_SPACE_PER_THREAD;
        limits.push(MemoryLimit {
            bytes: (limit - mapped - reserved).max(0.0),
            what: format!(
                "the address-space limit of this process, ulimit -v {}, less {} mapped already and {} kept for {threads} worker thread{}",
                human_bytes(limit),
                human_bytes(mapped),
                human_bytes(reserved),
                if threads == 1 { "" } else { "s" }
            ),
        });
    }
    if let Some(limit) = soft_limit_of(&limits_text, "Max data size") {
        let data = kilobytes_field(&status, "VmData").unwrap_or(0.0);
        limits.push(MemoryLimit {
            bytes: (limit - data).max(0.0),
            what: format!(
                "the data-size limit of this process, ulimit -d {}, less {} in use",
                human_bytes(limit),
                human_bytes(data)
            ),
        });
    }
    let cgroups = read(Path::new("/proc/self/cgroup")).unwrap_or_default();
    let mounts = read(Path::new("/proc/self/mountinfo")).unwrap_or_default();
    for (version, folder, mount_point) in memory_cgroup_folders(&cgroups, &mounts) {
        limits.extend(cgroup_limit(version, &folder, &mount_point, read));
    }
    limits
}

/// The memory budget from the machine's available memory (`None`: it does not say), an
/// explicit `--max-memory` and the process's limits: `--max-memory` takes the place of
/// the available memory, and no budget exceeds a limit of the process, which
/// `--max-memory` cannot raise.
pub fn budget_within(
    asked: Option<f64>,
    available: Option<f64>,
    limits: &[MemoryLimit],
    caller: Caller,
) -> (f64, String) {
    let option = caller.option("max_memory");
    let (mut bytes, mut source) = match (asked, available) {
        (Some(bytes), _) => (bytes, option.clone()),
        (None, Some(bytes)) => (
            bytes,
            format!("available on this machine; raise with {option}"),
        ),
        (None, None) => (
            4.0 * 1024.0_f64.powi(3),
            format!("a default of 4 GiB where the machine does not say; set {option}"),
        ),
    };
    if let Some(tightest) = limits
        .iter()
        .min_by(|a, b| a.bytes.total_cmp(&b.bytes))
        .filter(|limit| limit.bytes < bytes)
    {
        bytes = tightest.bytes;
        source = if asked.is_some() {
            format!("{}, which {option} cannot raise", tightest.what)
        } else {
            tightest.what.clone()
        };
    }
    (bytes, source)
}

/// The memory budget in bytes and where it comes from: `--max-memory`, or the memory the
/// kernel says is available (`MemAvailable` of /proc/meminfo), else 4 GiB; in either case
/// at most what the process's limits leave ([`process_limits`]) with `threads` workers.
pub fn memory_budget(asked: Option<f64>, threads: usize, caller: Caller) -> (f64, String) {
    // The kernel's files are small; a megabyte bounds them.
    let limit = ReadLimit {
        bytes: 1 << 20,
        source: "the bound of a kernel file".to_string(),
    };
    let read = |path: &Path| read_text(path, &limit).ok();
    let available =
        read(Path::new("/proc/meminfo")).and_then(|text| kilobytes_field(&text, "MemAvailable"));
    budget_within(asked, available, &process_limits(threads, &read), caller)
}

/// The bound of a scenario, report or baseline read whole: a quarter of the memory this
/// process may take (a JSON document takes several times its bytes once parsed), worked
/// out once.
pub fn whole_file_limit(caller: Caller) -> ReadLimit {
    let threads = cores() as usize;
    let (budget, source) = memory_budget(None, threads, caller);
    ReadLimit {
        bytes: (budget / 4.0) as u64,
        source: format!(
            "a quarter of the {} of memory ({source})",
            human_bytes(budget)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_bounded_by_the_cores() {
        let most = THREADS_PER_CORE * cores();
        assert_eq!(
            threads(Some(most), Caller::CommandLine).unwrap(),
            most as usize
        );
        let err = threads(Some(most + 1), Caller::CommandLine)
            .unwrap_err()
            .to_string();
        assert!(err.starts_with(&format!("--threads: {} is more than {most}", most + 1)));
    }
    /// /proc/self/limits as Linux writes it (the address space limited by `ulimit -v`).
    const LIMITS: &str =
        "Limit                     Soft Limit           Hard Limit           Units     
Max cpu time              unlimited            unlimited            seconds   
Max data size             unlimited            unlimited            bytes     
Max stack size            8388608              unlimited            bytes     
Max address space         6442450944           6442450944           bytes     
Max locked memory         65536                65536                bytes     
";

    #[test]
    fn the_soft_limits_are_read_from_proc_self_limits() {
        assert_eq!(
            soft_limit_of(LIMITS, "Max address space"),
            Some(6442450944.0)
        );
        assert_eq!(soft_limit_of(LIMITS, "Max data size"), None);
        assert_eq!(soft_limit_of(LIMITS, "Max resident set"), None);
        assert_eq!(soft_limit_of("", "Max address space"), None);
        let status = "Name:\trvtol\nVmPeak:\t  30000 kB\nVmSize:\t   20480 kB\nVmData:\t 1024 kB\n";
        assert_eq!(kilobytes_field(status, "VmSize"), Some(20480.0 * 1024.0));
        assert_eq!(kilobytes_field(status, "VmData"), Some(1024.0 * 1024.0));
        assert_eq!(
            kilobytes_field("MemAvailable:   1000 kB\n", "MemAvailable"),
            Some(1024000.0)
        );
        assert_eq!(kilobytes_field(status, "VmSwap"), None);
    }

    #[test]
    fn the_address_space_limit_counts_what_is_mapped_and_what_threads_reserve() {
        let files = |path: &Path| match path.to_str()? {
            "/proc/self/limits" => Some(LIMITS.to_string()),
            "/proc/self/status" => Some("VmSize:\t 102400 kB\nVmData:\t 2048 kB\n".to_string()),
            _ => None,
        };
        let limits = process_limits(2, &files);
        assert_eq!(limits.len(), 1, "{limits:?}");
        let expected = 6442450944.0 - 102400.0 * 1024.0 - 2.0 * ADDRESS_SPACE_PER_THREAD;
        assert_eq!(limits[0].bytes, expected);
        assert!(limits[0].what.starts_with("the address-space limit of this process, ulimit -v 6.4 GB, less 104.9 MB mapped already and 151.0 MB kept for 2 worker threads"), "{}", limits[0].what);
        // The budget is the limit's, whether or not --max-memory asks for more.
        let (bytes, source) = budget_within(None, Some(20e9), &limits, Caller::CommandLine);
        assert_eq!(bytes, expected);
        assert!(source.starts_with("the address-space limit"), "{source}");
        let (bytes, source) = budget_within(Some(10e9), Some(20e9), &limits, Caller::CommandLine);
        assert_eq!(bytes, expected);
        assert!(
            source.ends_with(", which --max-memory cannot raise"),
            "{source}"
        );
        // Below the limit, --max-memory or the available memory is the budget.
        assert_eq!(
            budget_within(Some(1e9), Some(20e9), &limits, Caller::CommandLine),
            (1e9, "--max-memory".to_string())
        );
        assert_eq!(
            budget_within(None, Some(2e9), &limits, Caller::CommandLine).0,
            2e9
        );
        assert_eq!(
            budget_within(None, None, &[], Caller::CommandLine).0,
            4.0 * 1024.0_f64.powi(3)
        );
    }

    #[test]
    fn the_cgroups_are_found_through_mountinfo() {
        // A hybrid machine: v1 controllers and the unified hierarchy beside them.
        let cgroup = "12:pids:/user.slice\n4:memory:/slurm/uid_1000/job_42/step_0\n0::/slurm/uid_1000/job_42\n";
        let mountinfo = "\
24 30 0:22 / /sys rw,nosuid,nodev,noexec,relatime shared:7 - sysfs sysfs rw
33 24 0:28 / /sys/fs/cgroup/unified rw,nosuid,nodev,noexec,relatime shared:10 - cgroup2 cgroup2 rw,nsdelegate
37 24 0:32 / /sys/fs/cgroup/memory rw,nosuid,nodev,noexec,relatime shared:15 - cgroup cgroup rw,memory
38 24 0:33 / /sys/fs/cgroup/pids rw,nosuid,nodev,noexec,relatime shared:16 - cgroup cgroup rw,pids
";
        let found = memory_cgroup_folders(cgroup, mountinfo);
        assert_eq!(
            found,
            vec![
                (
                    CgroupVersion::MemoryController,
                    PathBuf::from("/sys/fs/cgroup/memory/slurm/uid_1000/job_42/step_0"),
                    PathBuf::from("/sys/fs/cgroup/memory")
                ),
                (
                    CgroupVersion::Unified,
                    PathBuf::from("/sys/fs/cgroup/unified/slurm/uid_1000/job_42"),
                    PathBuf::from("/sys/fs/cgroup/unified")
                ),
            ]
        );
        // A container's cgroup namespace: its cgroup is the root of a mounted sub-tree.
        let container = memory_cgroup_folders(
            "0::/\n",
            "600 500 0:30 / /sys/fs/cgroup ro,nosuid - cgroup2 cgroup rw\n",
        );
        assert_eq!(
            container,
            vec![(
                CgroupVersion::Unified,
                PathBuf::from("/sys/fs/cgroup"),
                PathBuf::from("/sys/fs/cgroup")
            )]
        );
        // A mount of a sub-tree seen from outside it, with an escaped space.
        let sub_tree = memory_cgroup_folders(
            "0::/kubepods/pod1/c1\n",
            "600 500 0:30 /kubepods /mnt/my\\040cgroups rw - cgroup2 cgroup2 rw\n",
        );
        assert_eq!(sub_tree[0].1, PathBuf::from("/mnt/my cgroups/pod1/c1"));
        assert!(memory_cgroup_folders("3:cpu:/\n", mountinfo).is_empty());
    }

    #[test]
    fn a_cgroup_limit_is_the_tightest_of_its_ancestors_less_their_use() {
        let files = |path: &Path| {
            Some(
                match path.to_str()? {
                    "/sys/fs/cgroup/job/memory.max" => "1073741824\n",
                    "/sys/fs/cgroup/job/memory.current" => "104857600\n",
                    "/sys/fs/cgroup/job/memory.stat" => {
                        "anon 52428800\nfile 52428800\ninactive_file 41943040\n"
                    }
                    "/sys/fs/cgroup/job/step/memory.max" => "max\n",
                    "/sys/fs/cgroup/job/step/memory.current" => "1000\n",
                    "/sys/fs/cgroup/memory.max" => "536870912000\n",
                    _ => return None,
                }
                .to_string(),
            )
        };
        let limit = cgroup_limit(
            CgroupVersion::Unified,
            Path::new("/sys/fs/cgroup/job/step"),
            Path::new("/sys/fs/cgroup"),
            &files,
        )
        .expect("the job's limit");
        // 1 GiB less 100 MiB in use, of which 40 MiB inactive file cache.
        assert_eq!(limit.bytes, 1073741824.0 - 104857600.0 + 41943040.0);
        assert_eq!(
            limit.what,
            "the memory limit of this process's cgroup, /sys/fs/cgroup/job/memory.max 1.1 GB less 62.9 MB in use"
        );
        // cgroup v1: no limit is written as 2⁶³ − 4096.
        let v1 = |path: &Path| {
            Some(
                match path.to_str()? {
                    "/cg/memory/a/memory.limit_in_bytes" => "9223372036854771712",
                    "/cg/memory/a/b/memory.limit_in_bytes" => "268435456",
                    "/cg/memory/a/b/memory.usage_in_bytes" => "268435456",
                    "/cg/memory/a/b/memory.stat" => "cache 0\ntotal_inactive_file 1048576\n",
                    _ => return None,
                }
                .to_string(),
            )
        };
        let limit = cgroup_limit(
            CgroupVersion::MemoryController,
            Path::new("/cg/memory/a/b"),
            Path::new("/cg/memory"),
            &v1,
        )
        .expect("b's limit");
        assert_eq!(limit.bytes, 1048576.0);
        assert!(cgroup_limit(
            CgroupVersion::MemoryController,
            Path::new("/cg/memory/a"),
            Path::new("/cg/memory"),
            &v1
        )
        .is_none());
    }
}
