//! Firmware-style proof that `vcx` walks a complex with no std and no heap.
//!
//! The scene and its complex are one file in the binary complex format (`hall.vcx`,
//! embedded with `include_bytes!`; the host test `tests/tests/no_alloc.rs` checks that it
//! is what `vcx build` writes). At start the file is decoded and checked by
//! `format::decode_into` into static buffers (the scene validated into fixed-capacity
//! storage on the stack), the complex's derived state is rebuilt into a second static
//! block, and the view from each embedded viewpoint is walked into a fixed output buffer
//! (`app.rs`, which the host test runs on the same bytes and checks against the exact
//! reference). Then, from each viewpoint, a ray-tree frame (depth 4 through the hall's
//! mirrors, 90°, 64 columns) is walked in lock step through a static `TreeScratch` into a
//! static buffer of `render::FrameInterval`s and covered column by column (the host test
//! compares it with `walk::frame_tree` on an owned complex). Every failure is an
//! `app::Error`; nothing panics on the data.
//!
//! The stack is painted before each phase and scanned after it: the high-water marks are
//! left in [`STACK_USED`] for a debugger, and with the feature `qemu` (an MPS2 board under
//! QEMU, see `memory-qemu.x`) printed on UART0 with the checksums.
//!
//! `unsafe` here (the core forbids it): the take-once cell handing `main` the static RAM
//! blocks, and the volatile reads and writes of stack painting and the QEMU UART.
#![no_std]
#![no_main]

mod app;
mod stack;
#[rustfmt::skip]
mod viewpoints;

use core::cell::UnsafeCell;
use core::hint::black_box;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use cortex_m_rt::entry;
use panic_halt as _;

/// Bytes of stack (from painting), for a debugger to read: `main`'s own frames (with the
/// validated scene), and below them at most the setup (decoding and checking the file,
/// rebuilding the derived state), the view walks and the ray-tree frames.
pub static STACK_USED: [AtomicU32; 4] = [
    AtomicU32::new(0),
    AtomicU32::new(0),
    AtomicU32::new(0),
    AtomicU32::new(0),
];

/// A static that `main` takes once, mutably. Single core, and nothing but `main` calls
/// `take`, so a load and a store suffice (thumbv6m has no compare-and-swap).
struct TakeOnce<T> {
    taken: AtomicBool,
    value: UnsafeCell<T>,
}

// SAFETY: the value is only reached through `take`, which hands out one `&mut` at most.
unsafe impl<T: Send> Sync for TakeOnce<T> {}

impl<T> TakeOnce<T> {
    const fn new(value: T) -> Self {
        TakeOnce {
            taken: AtomicBool::new(false),
            value: UnsafeCell::new(value),
        }
    }

    // The cell hands out its one `&mut` at most once: what `mut_from_ref` warns about.
    #[allow(clippy::mut_from_ref)]
    fn take(&'static self) -> Option<&'static mut T> {
        if self.taken.load(Ordering::Relaxed) {
            return None;
        }
        self.taken.store(true, Ordering::Relaxed);
        // SAFETY: `taken` was false, so no reference to the value exists; it is now true,
        // so no other will be made.
        Some(unsafe { &mut *self.value.get() })
    }
}

/// The walk's RAM besides the stack, in statics so that `size -A` reports it: the decoded
/// arenas and the derived state (zero at start: `.bss`), the view's output buffer
/// (`.data`), the ray tree's scratch and the frame's intervals (empty at start: `.bss`).
static ARENAS: TakeOnce<app::Arenas> = TakeOnce::new(app::Arenas::new());
static RAM: TakeOnce<app::Ram> = TakeOnce::new(app::Ram::new());
static OUT: TakeOnce<app::Out> = TakeOnce::new(app::out());
static TREE: TakeOnce<app::TreeRam> = TakeOnce::new(app::TreeRam::new());
static FRAME: TakeOnce<app::Frame> = TakeOnce::new(app::Frame::new());

#[entry]
fn main() -> ! {
    // Phase 1: decode and check the file, rebuild the derived state; phase 2: the view
    // walks; phase 3: the ray-tree frames. The stack is painted before each phase and its
    // high-water mark read after it.
    let sp = stack::paint();
    let file = match ARENAS.take() {
        Some(arenas) => app::decode(app::VCX, arenas),
        None => Err(app::Error::Taken),
    };
    let complex = match (&file, RAM.take()) {
        (Ok(file), Some(ram)) => {
            app::complex(&file.scene.as_ref(), file.vertices, file.cylinders, ram)
        }
        (Err(e), _) => Err(*e),
        (_, None) => Err(app::Error::Taken),
    };
    let setup_stack = stack::used(sp);
    let sp = stack::paint();
    let result = match (&file, &complex, OUT.take()) {
        (Ok(file), Ok(complex), Some(out)) => {
            app::views(complex, &file.scene.as_ref(), out, |_, v| {
                black_box(v);
            })
        }
        (Err(e), _, _) | (_, Err(e), _) => Err(*e),
        (_, _, None) => Err(app::Error::Taken),
    };
    let walk_stack = stack::used(sp);
    let sp = stack::paint();
    let trees = match (&file, &complex, TREE.take(), FRAME.take()) {
        (Ok(file), Ok(complex), Some(scratch), Some(frame)) => app::trees(
            complex,
            &file.scene.as_ref(),
            scratch,
            frame,
            |_, _, f, _| {
                black_box(f);
            },
        ),
        (Err(e), _, _, _) | (_, Err(e), _, _) => Err(*e),
        (_, _, None, _) | (_, _, _, None) => Err(app::Error::Taken),
    };
    let tree_stack = stack::used(sp);
    STACK_USED[0].store(stack::above(sp), Ordering::Relaxed);
    STACK_USED[1].store(setup_stack, Ordering::Relaxed);
    STACK_USED[2].store(walk_stack, Ordering::Relaxed);
    STACK_USED[3].store(tree_stack, Ordering::Relaxed);
    #[cfg(feature = "qemu")]
    stack::report(
        stack::above(sp),
        [setup_stack, walk_stack, tree_stack],
        &result,
        &trees,
    );
    loop {
        black_box(&result);
        black_box(&trees);
        black_box(&STACK_USED);
    }
}
