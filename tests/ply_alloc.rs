//! A PLY header's element counts must never size an allocation: this test
//! binary counts every allocation and checks that a header claiming 10^12
//! vertices is refused without asking for more than a few kilobytes.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn huge_vertex_count_is_refused_without_allocating_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        // Nothing after the header.
        ("binary_little_endian", "1000000000000", ""),
        // Some vertices, far fewer than claimed.
        ("ascii", "1000000000000", "0 0 0\n1 0 0\n0 1 0\n"),
        // A count that still fits in u64 but not in usize arithmetic.
        ("binary_big_endian", "18446744073709551615", ""),
    ];
    for (format, count, body) in cases {
        let text = format!(
            "ply\nformat {format} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n{body}"
        );
        let path = dir.path().join(format!("{format}.ply"));
        std::fs::write(&path, text).unwrap();
        LARGEST.store(0, Ordering::Relaxed);
        let err = raytracer::scene::mesh::load_mesh(&path).unwrap_err().to_string();
        let largest = LARGEST.load(Ordering::Relaxed);
        assert!(largest < 64 * 1024, "{format}: an allocation of {largest} bytes");
        assert!(
            err.contains(":3:") && err.contains(&format!("declares {count} items")),
            "{err}"
        );
    }
}
