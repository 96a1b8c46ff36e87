//! Stack painting: fill the unused stack with a pattern before the walk, find the deepest
//! overwritten word after it. The stack grows down from `_stack_start` (the end of RAM)
//! towards `__sheap` (the end of `.bss`), both from cortex-m-rt's linker script.

const PATTERN: u32 = 0x5A5A_A5A5;
/// Words left unpainted below the painter's own frame.
const MARGIN: usize = 64;

extern "C" {
    static mut __sheap: u32;
    static mut _stack_start: u32;
}

fn bounds() -> (usize, usize) {
    // Only the addresses of the linker symbols are taken.
    (
        core::ptr::addr_of!(__sheap) as usize,
        core::ptr::addr_of!(_stack_start) as usize,
    )
}

/// Paints the free stack below the caller's frame; returns the stack pointer there (about
/// the caller's stack pointer).
#[inline(never)]
pub fn paint() -> usize {
    let here = 0u32;
    let sp = core::hint::black_box(core::ptr::addr_of!(here)) as usize;
    let (bottom, _) = bounds();
    let mut p = bottom;
    while p + 4 * MARGIN < sp {
        // SAFETY: [bottom, sp − margin) is free stack: above `.bss`, below every live frame.
        unsafe { core::ptr::write_volatile(p as *mut u32, PATTERN) };
        p += 4;
    }
    sp
}

/// Bytes of stack used below `from` (what [`paint`] returned) since it painted: from there
/// down to the deepest overwritten word.
#[inline(never)]
pub fn used(from: usize) -> u32 {
    let (bottom, top) = bounds();
    let mut p = bottom;
    // SAFETY: reads of words in the stack region, between `.bss` and the end of RAM.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PATTERN {
        p += 4;
    }
    from.saturating_sub(p) as u32
}

/// Bytes of stack from the top down to `sp` (the frames of the reset handler and `main`).
pub fn above(sp: usize) -> u32 {
    bounds().1.saturating_sub(sp) as u32
}

/// Prints the stack high-water marks and the result on the MPS2's UART0 (CMSDK APB UART).
#[cfg(feature = "qemu")]
pub fn report(
    main: u32,
    [setup, walk, trees]: [u32; 3],
    views: &Result<u32, crate::app::Error>,
    frames: &Result<u32, crate::app::Error>,
) {
    use core::fmt::Write;
    struct Uart;
    const UART0: usize = 0x4000_4000;
    impl Write for Uart {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for b in s.bytes() {
                // SAFETY: the CMSDK UART's data register (QEMU's MPS2 boards).
                unsafe {
                    while core::ptr::read_volatile((UART0 + 4) as *const u32) & 1 != 0 {}
                    core::ptr::write_volatile(UART0 as *mut u32, u32::from(b));
                }
            }
            Ok(())
        }
    }
    // SAFETY: enable the transmitter (CTRL bit 0) with a valid baud divisor.
    unsafe {
        core::ptr::write_volatile((UART0 + 0x10) as *mut u32, 16);
        core::ptr::write_volatile((UART0 + 8) as *mut u32, 1);
    }
    use core::mem::size_of;
    let _ = writeln!(
        Uart,
        "vcx-firmware: size_of Angle {} B, ViewInterval {} B, Cylinder {} B, Vertex {} B, \
         Slots {} B, Arenas {} B, Ram {} B, Out {} B, FrameInterval {} B, \
         TreeRam ({} walks, {} splits, {} hops) {} B, depth-5 TreeScratch<6, 5> {} B, \
         Frame ({} intervals) {} B",
        size_of::<vcx::geom::sos::Angle>(),
        size_of::<vcx::walk::ViewInterval>(),
        size_of::<vcx::partition::Cylinder>(),
        size_of::<vcx::partition::Vertex>(),
        size_of::<vcx::partition::Slots>(),
        size_of::<crate::app::Arenas>(),
        size_of::<crate::app::Ram>(),
        size_of::<crate::app::Out>(),
        size_of::<vcx::render::FrameInterval>(),
        crate::app::TREE_WALKS,
        crate::app::TREE_SPLITS,
        crate::app::TREE_HOPS,
        size_of::<crate::app::TreeRam>(),
        // The depth-5 tree through mirrors of the device-format issue's RAM target.
        size_of::<vcx::walk::TreeScratch<6, 5>>(),
        crate::app::FRAME_CAPACITY,
        size_of::<crate::app::Frame>(),
    );
    let _ = writeln!(
        Uart,
        "vcx-firmware: stack: main {main} B, below it setup {setup} B, view walks {walk} B, \
         ray-tree frames {trees} B; checksums: views {views:?}, frames {frames:?}"
    );
}
