//! `c2warp animate`'s two halves on the built-in lizard (746 × 669 pixels, C², 20k
//! vertices) and its three-key walk (`assets/lizard-walk.json`):
//!
//! * `animate/draw/threads=N`: 24 frames drawn through [`Animator::for_each_frame`]
//!   (posed, warped on the CPU; the frames dropped) in a pool of 1 and 2 threads: how
//!   drawing scales with cores;
//! * `animate/one-by-one/threads=N`: the same frames drawn one after the other
//!   ([`Animator::render`]), each split into bands of rows by the warp alone: what
//!   drawing whole frames side by side gains over that;
//! * `animate/encode/FORMAT`: 24 frames already drawn, written by
//!   [`render::AnimationWriter`] to a temporary folder four at a time (each four
//!   compressed side by side, as the animator's writer thread hands them over): what
//!   each encoder costs a frame.
//!
//! ```sh
//! cargo bench -p pipeline --bench animate
//! ```
//! End to end, `c2warp animate assets/lizard-walk.json -o walk.png --to 4.99` (120
//! frames) with `RAYON_NUM_THREADS=1` and `2` ([performance](../../../docs/performance.md)).

use std::sync::atomic::AtomicBool;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pipeline::animate::{Animator, Span, plan};
use project::Project;
use render::{AnimationFormat, AnimationWriter, Picture};

const FRAMES: usize = 24;

fn animate(c: &mut Criterion) {
    let picture = render::decode_picture(pipeline::DEFAULT_IMAGE, &render::ImageLimits::default())
        .expect("the built-in picture");
    let project =
        Project::from_json(include_str!("../../../assets/lizard-walk.json")).expect("the walk");
    // 24 frames spread over the walk's 5 s.
    let span = Span {
        fps: Some(FRAMES as f64 / 5.0),
        from: None,
        to: Some(5.0 - 1e-3),
    };
    let frames = plan(&project, span, AnimationFormat::Apng).expect("a plan");
    assert_eq!(frames.times.len(), FRAMES);
    let mut animator = Animator::new(&picture, &project, &frames, false, &()).expect("set up");
    let none = AtomicBool::new(false);

    let mut group = c.benchmark_group("animate");
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(3));
    group.throughput(Throughput::Elements(FRAMES as u64));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        group.bench_function(format!("draw/threads={threads}"), |b| {
            b.iter(|| {
                pool.install(|| {
                    animator.for_each_frame(
                        &frames.times,
                        &mut |_, pictures| {
                            drop(std::hint::black_box(pictures));
                            Ok(())
                        },
                        &none,
                    )
                })
                .expect("drawn");
            });
        });
        group.bench_function(format!("one-by-one/threads={threads}"), |b| {
            b.iter(|| {
                pool.install(|| {
                    for &time in &frames.times {
                        drop(std::hint::black_box(animator.render(time).expect("drawn")));
                    }
                });
            });
        });
    }

    let mut drawn: Vec<Picture> = Vec::new();
    animator
        .for_each_frame(
            &frames.times,
            &mut |_, pictures| {
                drawn.extend(pictures);
                Ok(())
            },
            &none,
        )
        .expect("drawn");
    let dir = tempfile::tempdir().expect("a folder");
    let (width, height) = animator.size();
    for (name, file) in [
        ("apng", "walk.png"),
        ("webp", "walk.webp"),
        ("gif", "walk.gif"),
        ("sequence", "walk/"),
    ] {
        let path = dir.path().join(file);
        let format = AnimationFormat::from_path(&path).expect("a format");
        group.bench_function(format!("encode/{name}"), |b| {
            b.iter(|| {
                let mut writer =
                    AnimationWriter::create(&path, format, width, height, FRAMES, frames.fps)
                        .expect("created");
                for pictures in drawn.chunks(4) {
                    writer.push_all(pictures).expect("pushed");
                }
                writer.finish().expect("written");
            });
        });
    }
    group.finish();
}

criterion_group!(benches, animate);
criterion_main!(benches);
