//! Memory a request will need, checked against the memory available before anything is
//! allocated: a request that cannot fit is refused at once with what it needs and what there
//! is, instead of being killed by the operating system minutes in (issue #16).
//!
//! The figures are the measured peaks, rounded up: the render's per-pixel buffers
//! ([`crate::render::image_bytes`]), the BVH build ([`BVH_BYTES_PER_TRIANGLE`]) and the photon map's build
//! (`PhotonMethod::peak_build_bytes`).
//!
//! What is available is the smaller of the machine's `MemAvailable` and what the process's
//! cgroups leave below their memory limits: under Slurm's `--mem`, a container's `--memory` or
//! a systemd slice, the machine may have plenty free while the job is killed at its limit
//! (issue #24). Both cgroup versions are read: v2's `memory.max` less `memory.current`, v1's
//! `memory.limit_in_bytes` less `memory.usage_in_bytes`, for the process's cgroup and each
//! of its ancestors (a parent's limit binds its children too). The page cache the kernel would
//! drop before killing anything (`inactive_file` of `memory.stat`) counts as available, as
//! container runtimes count it. An address-space limit (`ulimit -v`, RLIMIT_AS, as
//! `proc/self/limits` gives it) binds too: what it leaves is the limit less the process's
//! `VmSize`. Where nothing can be read (no `/proc`), nothing is refused; nor where
//! [`NO_CHECK`] is set.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Peak memory of building the BVH, per triangle, beyond the mesh itself: 290 B measured with
/// obvhs's best preset on a 5 M-triangle sphere (210 B with our binned SAH builder).
pub const BVH_BYTES_PER_TRIANGLE: u128 = 320;

/// Set to 1 to skip the checks (where you know the estimate is wrong for your system); an
/// allocation that then fails still ends the CLI with status 2 and its temporaries removed.
pub const NO_CHECK: &str = "HMDIST_NO_MEMORY_CHECK";

/// Where the available memory's bound comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// The machine's `MemAvailable` (`/proc/meminfo`).
    Machine,
    /// A cgroup's memory limit (Slurm `--mem`, a container's limit).
    Cgroup,
    /// The process's address-space limit (`ulimit -v`, RLIMIT_AS).
    AddressSpace,
}

/// Bytes this process can still allocate, and what bounds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Available {
    /// Bytes that can still be allocated.
    pub bytes: u128,
    /// Whether the machine or a cgroup's limit sets them.
    pub bound: Bound,
}

/// The memory this process can still allocate (see the module docs), where it can be known.
pub fn available() -> Option<u128> {
    available_under(Path::new("/")).map(|a| a.bytes)
}

/// [`available`] read from the files under `root` (`/` but in tests): `proc/meminfo`,
/// `proc/self/cgroup` and the cgroup file systems under `sys/fs/cgroup`, `proc/self/limits`
/// and `proc/self/status`.
pub fn available_under(root: &Path) -> Option<Available> {
    let bounds = [
        (meminfo_available(root), Bound::Machine),
        (cgroup_available(root), Bound::Cgroup),
        (address_space_available(root), Bound::AddressSpace),
    ];
    bounds
        .into_iter()
        .filter_map(|(bytes, bound)| Some(Available { bytes: bytes?, bound }))
        .min_by_key(|a| a.bytes)
}

/// The soft address-space limit of `proc/self/limits` less the `VmSize` of
/// `proc/self/status`, where there is a limit.
fn address_space_available(root: &Path) -> Option<u128> {
    let limits = std::fs::read_to_string(root.join("proc/self/limits")).ok()?;
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    // "Max address space   <soft>   <hard>   bytes"; the soft one is what binds.
    let limit: u128 = line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let status = std::fs::read_to_string(root.join("proc/self/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kb: u128 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(limit.saturating_sub(kb * 1024))
}

/// `MemAvailable` of `proc/meminfo`.
fn meminfo_available(root: &Path) -> Option<u128> {
    let info = std::fs::read_to_string(root.join("proc/meminfo")).ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u128 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The least room below a memory limit among the process's cgroups and their ancestors.
fn cgroup_available(root: &Path) -> Option<u128> {
    let membership = std::fs::read_to_string(root.join("proc/self/cgroup")).ok()?;
    let mut least: Option<u128> = None;
    for line in membership.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (fields.next(), fields.next(), fields.next()) else {
            continue;
        };
        let path = path.trim().trim_start_matches('/');
        // v2 (one hierarchy, "0::/path"): mounted at sys/fs/cgroup, or at
        // sys/fs/cgroup/unified beside v1 controllers ("hybrid" systems). v1: the memory
        // controller's own mount.
        let (mounts, files): (&[&str], _) = if id == "0" && controllers.is_empty() {
            (&["sys/fs/cgroup", "sys/fs/cgroup/unified"], V2)
        } else if controllers.split(',').any(|c| c == "memory") {
            (&["sys/fs/cgroup/memory"], V1)
        } else {
            continue;
        };
        for mount in mounts {
            let mount = root.join(mount);
            for dir in cgroup_and_ancestors(&mount, path) {
                if let Some(room) = room_below_limit(&dir, files) {
                    least = Some(least.map_or(room, |l| l.min(room)));
                }
            }
        }
    }
    least
}

/// A cgroup version's file names: limit, usage, and the page-cache key in `memory.stat`.
type Files = (&'static str, &'static str, &'static str);
const V2: Files = ("memory.max", "memory.current", "inactive_file");
const V1: Files = (
    "memory.limit_in_bytes",
    "memory.usage_in_bytes",
    "total_inactive_file",
);

/// `mount/path` and each directory above it up to `mount` (inside a container, the path the
/// process sees may not exist in its mount, whose root is then its own cgroup).
fn cgroup_and_ancestors(mount: &Path, path: &str) -> Vec<PathBuf> {
    let mut dirs = vec![mount.to_path_buf()];
    let mut dir = mount.to_path_buf();
    for part in path.split('/').filter(|p| !p.is_empty()) {
        dir.push(part);
        dirs.push(dir.clone());
    }
    dirs
}

/// Limit less usage (less reclaimable page cache) in one cgroup directory, if it has a limit.
fn room_below_limit(dir: &Path, (limit, usage, cache): Files) -> Option<u128> {
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    // "max" (v2) or v1's 2⁶³-rounded "unlimited" parse as no limit or as more than any machine.
    let limit: u128 = read(limit)?.trim().parse().ok()?;
    if limit >= 1 << 62 {
        return None;
    }
    let usage: u128 = read(usage)?.trim().parse().ok()?;
    let reclaimable: u128 = read("memory.stat")
        .and_then(|stat| {
            stat.lines()
                .find_map(|l| l.strip_prefix(cache)?.strip_prefix(' ')?.trim().parse().ok())
        })
        .unwrap_or(0);
    Some(limit.saturating_sub(usage.saturating_sub(reclaimable)))
}

/// Refuses `needed` bytes for `what` where more than `available` bytes (or, for `None`, the
/// memory available now) would be needed: a [`Error::Parameter`] on `parameter` (`None`:
/// [`Error::Scene`]), saying how much is needed and how much there is.
pub fn check(
    parameter: Option<&'static str>,
    what: &str,
    needed: u128,
    available: Option<u128>,
) -> Result<()> {
    let available = match available {
        Some(bytes) => Available {
            bytes,
            bound: Bound::Machine,
        },
        None if std::env::var_os(NO_CHECK).is_some_and(|v| !v.is_empty() && v != "0") => return Ok(()),
        None => match available_under(Path::new("/")) {
            Some(a) => a,
            None => return Ok(()),
        },
    };
    check_against(parameter, what, needed, available)
}

fn check_against(
    parameter: Option<&'static str>,
    what: &str,
    needed: u128,
    available: Available,
) -> Result<()> {
    if needed <= available.bytes {
        return Ok(());
    }
    let under = match available.bound {
        Bound::Machine => "",
        Bound::Cgroup => " under this job's memory limit (its cgroup's; Slurm --mem, a container's limit)",
        Bound::AddressSpace => " under this process's address-space limit (ulimit -v)",
    };
    let message = format!(
        "{what} needs about {:.1} GB of memory, but only {:.1} GB is available{under}",
        needed as f64 / 1e9,
        available.bytes as f64 / 1e9
    );
    Err(match parameter {
        Some(name) => Error::invalid(name, message),
        None => Error::scene(message),
    })
}

/// Refuses a BVH over `triangles` triangles that would not fit in the memory available now.
pub fn check_bvh(triangles: usize) -> Result<()> {
    let what = format!("the BVH of the scene's {triangles} triangles");
    check(None, &what, triangles as u128 * BVH_BYTES_PER_TRIANGLE, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_over_the_available_memory_is_refused_saying_what_it_needs() {
        let gb = 1_000_000_000;
        assert!(check(Some("size"), "x", 2 * gb, Some(2 * gb)).is_ok());
        let e = check(Some("size"), "8192x8192", 3 * gb, Some(2 * gb)).unwrap_err();
        let expected =
            "bad parameter: size 8192x8192 needs about 3.0 GB of memory, but only 2.0 GB is available";
        assert_eq!(e.to_string(), expected);
        let e = check(None, "the BVH", 5 * gb, Some(gb)).unwrap_err();
        assert!(matches!(e, Error::Scene(_)), "{e}");
    }

    /// A fake file-system root with these files (relative path, contents).
    fn fake_root(name: &str, files: &[(&str, &str)]) -> PathBuf {
        let root = std::env::temp_dir().join(format!("hmdist-memory-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        for (path, contents) in files {
            let path = root.join(path);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, contents).unwrap();
        }
        root
    }

    const MEMINFO: (&str, &str) = (
        "proc/meminfo",
        "MemTotal: 67108864 kB\nMemAvailable: 33554432 kB\n",
    );
    const GIB: u128 = 1 << 30;

    #[test]
    fn a_cgroup_v2_limit_below_the_machines_free_memory_is_what_is_available() {
        // Slurm's --mem=4G on a machine with 32 GiB free: 1 GiB used, of which 256 MiB is
        // cache the kernel would drop, and a looser limit on the parent.
        let root = fake_root(
            "v2",
            &[
                MEMINFO,
                ("proc/self/cgroup", "0::/slurm/job_7/step_0\n"),
                ("sys/fs/cgroup/slurm/job_7/memory.max", "8589934592\n"),
                ("sys/fs/cgroup/slurm/job_7/memory.current", "0\n"),
                ("sys/fs/cgroup/slurm/job_7/step_0/memory.max", "4294967296\n"),
                ("sys/fs/cgroup/slurm/job_7/step_0/memory.current", "1073741824\n"),
                (
                    "sys/fs/cgroup/slurm/job_7/step_0/memory.stat",
                    "anon 805306368\ninactive_file 268435456\n",
                ),
                ("sys/fs/cgroup/slurm/memory.max", "max\n"),
                ("sys/fs/cgroup/slurm/memory.current", "5\n"),
            ],
        );
        let a = available_under(&root).unwrap();
        assert_eq!(
            a,
            Available {
                bytes: 4 * GIB - 768 * (1 << 20),
                bound: Bound::Cgroup
            }
        );
        // The refusal says where the limit comes from.
        let e = check_against(Some("size"), "8192x8192", 5 * GIB, a).unwrap_err();
        assert!(e.to_string().contains("memory limit"), "{e}");
        // A tighter parent binds.
        std::fs::write(root.join("sys/fs/cgroup/slurm/memory.max"), "1073741829\n").unwrap();
        assert_eq!(available_under(&root).unwrap().bytes, GIB);
        // No limit anywhere: the machine's figure.
        for dir in ["slurm", "slurm/job_7", "slurm/job_7/step_0"] {
            std::fs::write(root.join("sys/fs/cgroup").join(dir).join("memory.max"), "max\n").unwrap();
        }
        let a = available_under(&root).unwrap();
        assert_eq!(
            a,
            Available {
                bytes: 32 * GIB,
                bound: Bound::Machine
            }
        );
        std::fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn a_cgroup_v1_memory_limit_counts_and_unlimited_ones_do_not() {
        // v1 as this machine has it, hybrid: a v2 line with no memory files, and the memory
        // controller's hierarchy whose root reports v1's "unlimited" (2^63 rounded to a page).
        let root = fake_root(
            "v1",
            &[
                MEMINFO,
                (
                    "proc/self/cgroup",
                    "9:name=systemd:/\n4:cpu,memory:/batch/job\n0::/\n",
                ),
                (
                    "sys/fs/cgroup/memory/memory.limit_in_bytes",
                    "9223372036854771712\n",
                ),
                ("sys/fs/cgroup/memory/memory.usage_in_bytes", "99999999\n"),
                (
                    "sys/fs/cgroup/memory/batch/job/memory.limit_in_bytes",
                    "2147483648\n",
                ),
                (
                    "sys/fs/cgroup/memory/batch/job/memory.usage_in_bytes",
                    "1073741824\n",
                ),
                (
                    "sys/fs/cgroup/memory/batch/job/memory.stat",
                    "cache 9\ntotal_inactive_file 1073741824\n",
                ),
            ],
        );
        assert_eq!(
            available_under(&root).unwrap(),
            Available {
                bytes: 2 * GIB,
                bound: Bound::Cgroup
            }
        );
        std::fs::remove_dir_all(root).unwrap();
        // No cgroup files: MemAvailable alone; nothing at all: unknown.
        let root = fake_root("none", &[MEMINFO]);
        assert_eq!(available_under(&root).unwrap().bound, Bound::Machine);
        std::fs::remove_dir_all(&root).unwrap();
        assert_eq!(available_under(&root), None);
    }

    #[test]
    fn an_address_space_limit_binds_less_what_the_process_has_mapped() {
        // `ulimit -v 1000000` (KiB) with 200 MiB already mapped, on a machine with 32 GiB free.
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max cpu time              unlimited            unlimited            seconds   \n\
                      Max address space         1024000000           unlimited            bytes     \n";
        let root = fake_root(
            "rlimit",
            &[
                MEMINFO,
                ("proc/self/limits", limits),
                (
                    "proc/self/status",
                    "Name:\thmdist\nVmPeak:\t  300000 kB\nVmSize:\t  204800 kB\n",
                ),
            ],
        );
        let a = available_under(&root).unwrap();
        assert_eq!(
            a,
            Available {
                bytes: 1_024_000_000 - 200 * (1 << 20),
                bound: Bound::AddressSpace
            }
        );
        let e = check_against(Some("size"), "8192x8192", 2 * GIB, a).unwrap_err();
        assert!(e.to_string().contains("address-space limit (ulimit -v)"), "{e}");
        // "unlimited": the machine's figure.
        std::fs::write(
            root.join("proc/self/limits"),
            limits.replace("1024000000", "unlimited"),
        )
        .unwrap();
        assert_eq!(available_under(&root).unwrap().bound, Bound::Machine);
        std::fs::remove_dir_all(root).unwrap();
    }
}
