//! Forward kinematics and point colliders allocate nothing once their buffers exist.

use kinsynth::scenario::preset::{generate, Preset};
use kinsynth::Scenario;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn fk_and_colliders_do_not_allocate() {
    let s = Scenario::from_spec(&generate(Preset::Paper3d, 2)).unwrap();
    let chain = s.space.largest().chain();
    let mut frames = chain.frames();
    let mut colliders = Vec::new();
    let a: Vec<f64> = chain
        .free_axes()
        .iter()
        .map(|f| 0.3 * f.range.max)
        .collect();
    chain.fk(&a, &mut frames);
    chain.colliders(&frames, &mut colliders); // sizes the buffer once
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for _ in 0..100 {
        chain.fk(&a, &mut frames);
        chain.colliders(&frames, &mut colliders);
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(after - before, 0, "allocations inside fk/colliders");
    assert_eq!(colliders.len(), 8 * 4);
}
