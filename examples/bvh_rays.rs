//! BVH benchmark on `cornell-bunny`: builds the scene, generates the three ray
//! sets (512x512x4 jittered primary rays, 2^20 incoherent rays inside the box,
//! 2^20 shadow rays from the floor to the light), optionally writes them with
//! the triangles to a binary file for `bench/embree/embree_bench.c`, and times
//! our BVH and the `obvhs` crate's CWBVH on them, single-threaded.
//!
//! ```text
//! cargo run --release --example bvh_rays -- [--write FILE] [--reps N] [--builds N] [--ours-only] [--set NAME]
//! ```
//!
//! `--reps 0` skips the ray sets and times the builds only; `--set NAME`
//! (primary, incoherent or shadow) times that set alone, for counting one
//! query's instructions.
//!
//! Lines starting with `build` and `result` are read by `bench/bvh-vs-embree.sh`.
//! Builds are timed on the wall clock (median; single-threaded ones also in
//! the thread's CPU time), ray sets in the thread's CPU time (best of `--reps`
//! passes), so that other work on a shared machine counts as little as it can.

#[path = "../benches/common/mod.rs"]
mod common;

use common::{BenchRay, Query, RaySet};
use glam_obvhs::Vec3A;
use raytracer::geometry::{Bvh, Triangle};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

struct Args {
    write: Option<PathBuf>,
    reps: usize,
    builds: usize,
    /// Skip the obvhs crate (quicker runs while tuning ours).
    ours_only: bool,
    /// Time only the ray set of this name.
    set: Option<String>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        write: None,
        reps: 5,
        builds: 9,
        ours_only: false,
        set: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{k} needs a value"));
        match k.as_str() {
            "--write" => a.write = Some(PathBuf::from(value()?)),
            "--reps" => a.reps = value()?.parse().map_err(|e| format!("--reps: {e}"))?,
            "--builds" => a.builds = value()?.parse().map_err(|e| format!("--builds: {e}"))?,
            "--ours-only" => a.ours_only = true,
            "--set" => a.set = Some(value()?),
            _ => return Err(format!("unknown option {k}")),
        }
    }
    a.builds = a.builds.max(1);
    Ok(a)
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

/// Runs `query` over all rays `reps` times; returns the hit count and the
/// best time. Time is this thread's CPU time, so that other work sharing the
/// machine does not count (Embree's side measures the same way).
fn time_set(set: &RaySet, reps: usize, mut query: impl FnMut(&BenchRay) -> bool) -> (usize, Duration) {
    let mut best = Duration::MAX;
    let mut hits = 0;
    for _ in 0..reps {
        let start = cpu_time::ThreadTime::now();
        hits = set.rays.iter().filter(|r| query(r)).count();
        best = best.min(start.elapsed());
    }
    (hits, best)
}

fn report(name: &str, set: &RaySet, hits: usize, time: Duration) {
    println!(
        "result impl={name} set={} rays={} hits={hits} mrays_per_s={:.3}",
        set.name,
        set.rays.len(),
        set.rays.len() as f64 / time.as_secs_f64() / 1e6
    );
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("bvh_rays: {e}");
            return ExitCode::from(2);
        }
    };
    let desc = match common::cornell_bunny_scene() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("bvh_rays: cannot build cornell-bunny: {e}");
            return ExitCode::from(2);
        }
    };
    let world = common::world_triangles(&desc);
    // `--reps 0` times builds only.
    let mut sets = if args.reps > 0 || args.write.is_some() {
        common::standard_ray_sets(&desc)
    } else {
        vec![]
    };
    if let Some(name) = &args.set {
        if !sets.iter().any(|s| s.name == name.as_str()) {
            eprintln!("bvh_rays: --set: no ray set named {name}");
            return ExitCode::from(2);
        }
        sets.retain(|s| s.name == name.as_str());
    }
    if let Some(path) = &args.write {
        if let Err(e) = common::write_ray_file(path, &world, &sets) {
            eprintln!("bvh_rays: {}: {e}", path.display());
            return ExitCode::from(2);
        }
        println!(
            "wrote {} triangles and {} ray sets to {}",
            world.len(),
            sets.len(),
            path.display()
        );
    }

    // Ours: build time with the default thread pool, and with one thread both
    // on the wall clock and in that thread's CPU time.
    let tris: Vec<Triangle> = world.iter().map(|v| Triangle::new(v[0], v[1], v[2])).collect();
    let threads = rayon::current_num_threads();
    let (wall, process): (Vec<_>, Vec<_>) = (0..args.builds)
        .map(|_| {
            let cpu = cpu_time::ProcessTime::now();
            let (_, wall) = timed(|| Bvh::build(&tris));
            (wall, cpu.elapsed())
        })
        .unzip();
    println!(
        "build impl=ours threads={threads} triangles={} ms={:.2} process_cpu_ms={:.2}",
        tris.len(),
        median(wall).as_secs_f64() * 1e3,
        median(process).as_secs_f64() * 1e3
    );
    if let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() {
        let (wall, cpu) = pool.install(|| build_times(args.builds, || Bvh::build(&tris)));
        println!(
            "build impl=ours threads=1 triangles={} ms={:.2} cpu_ms={:.2}",
            tris.len(),
            wall.as_secs_f64() * 1e3,
            cpu.as_secs_f64() * 1e3
        );
    }
    let bvh = Bvh::build(&tris);
    let st = bvh.stats();
    println!(
        "stats impl=ours nodes={} leaves={} depth={} sah_cost={:.2} mib={:.2}",
        st.nodes,
        st.leaves,
        st.depth,
        st.sah_cost,
        st.bytes as f64 / (1 << 20) as f64
    );
    for set in sets.iter().filter(|_| args.reps > 0) {
        let (hits, time) = match set.query {
            Query::Closest => time_set(set, args.reps, |r| bvh.intersect(&r.ray, r.t_min, r.t_max).is_some()),
            Query::Occluded => time_set(set, args.reps, |r| bvh.occluded(&r.ray, r.t_min, r.t_max)),
        };
        report("ours", set, hits, time);
    }

    if args.ours_only {
        return ExitCode::SUCCESS;
    }

    // obvhs: CWBVH with its medium preset ("around Embree's build time"),
    // triangles laid out in its primitive order, one thread.
    let otris: Vec<obvhs::triangle::Triangle> = world
        .iter()
        .map(|v| obvhs::triangle::Triangle {
            v0: Vec3A::from_array(v[0].to_array()),
            v1: Vec3A::from_array(v[1].to_array()),
            v2: Vec3A::from_array(v[2].to_array()),
        })
        .collect();
    let obuild = || {
        obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &otris,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        )
    };
    let (wall, cpu) = build_times(args.builds, obuild);
    println!(
        "build impl=obvhs threads=1 triangles={} ms={:.2} cpu_ms={:.2}",
        otris.len(),
        wall.as_secs_f64() * 1e3,
        cpu.as_secs_f64() * 1e3
    );
    let cw = obuild();
    let ordered: Vec<_> = cw.primitive_indices.iter().map(|&i| otris[i as usize]).collect();
    let oray = |r: &BenchRay| {
        obvhs::ray::Ray::new(
            Vec3A::from_array(r.ray.o.to_array()),
            Vec3A::from_array(r.ray.d.to_array()),
            r.t_min,
            r.t_max,
        )
    };
    for set in sets.iter().filter(|_| args.reps > 0) {
        let (hits, time) = match set.query {
            Query::Closest => time_set(set, args.reps, |r| {
                let mut hit = obvhs::ray::RayHit::none();
                cw.ray_traverse(oray(r), &mut hit, |ray, id| ordered[id].intersect(ray))
            }),
            Query::Occluded => time_set(set, args.reps, |r| {
                !cw.ray_traverse_miss(oray(r), |ray, id| ordered[id].intersect(ray))
            }),
        };
        report("obvhs", set, hits, time);
    }
    ExitCode::SUCCESS
}

/// Median wall-clock and thread CPU time of `n` single-threaded builds.
fn build_times<T>(n: usize, build: impl Fn() -> T) -> (Duration, Duration) {
    let (wall, cpu): (Vec<_>, Vec<_>) = (0..n)
        .map(|_| {
            let cpu = cpu_time::ThreadTime::now();
            let (_, wall) = timed(&build);
            (wall, cpu.elapsed())
        })
        .unzip();
    (median(wall), median(cpu))
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let v = f();
    (v, start.elapsed())
}
