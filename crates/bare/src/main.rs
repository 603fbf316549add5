//! The onboard stack with nothing under it: no `std`, no heap, no C runtime.
//!
//! Real XV-11 bytes go through the sans-I/O decoder, each completed revolution through the ICL
//! odometry, and every 2 ms step through the autopilot, as on a flight controller; all state is
//! one `static`. If anything in `plumbline-core` or its dependencies pulled in `std`, this would
//! not link (a second panic handler, missing symbols), so building it is the proof that core is
//! no_std. `size target/release/plumbline-bare` then gives what the XV-11 configuration costs:
//! `.bss` + `.data` is its static RAM, `.text` its code.
//!
//! On x86-64 Linux it also runs: `_start` below stands in for a board's reset handler, and the
//! binary prints what it did and how much stack it used, and exits with 0 only if the stack
//! decoded the revolutions, matched scans and kept every motor command finite. A board crate
//! supplies its own entry instead.
#![no_std]
#![no_main]
// The memory functions below must not be compiled into calls to themselves.
#![no_builtins]

use core::hint::black_box;
use core::mem::MaybeUninit;
use plumbline_core::flight::autopilot::AutopilotConfig;
use plumbline_core::flight::onboard::Onboard;
use plumbline_core::lidar::xv11_revolution::Xv11Decoder;
use plumbline_core::matching::OdometryConfig;
use plumbline_core::msgs::{ImuSample, Inputs, PilotInput, GRAVITY_M_S2};

/// Beams of an XV-11 revolution.
const BEAMS: usize = 360;

/// The onboard step period (s): 500 Hz, the IMU's rate.
const DT_S: f32 = 0.002;

/// Bytes the XV-11 sends in one step: 90 packets of 22 bytes a revolution at about 5 Hz is
/// 9.9 KB/s, 20 bytes every 2 ms.
const BYTES_PER_STEP: usize = 20;

/// The first revolutions of the bundled real capture (`build.rs`).
static CAPTURE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/capture.bin"));

/// Everything the vehicle keeps between steps.
struct Vehicle {
    decoder: Xv11Decoder,
    onboard: Onboard<BEAMS>,
}

/// The vehicle's state, in `.bss`: zeroed at load, written once by [`start`].
static mut VEHICLE: MaybeUninit<Vehicle> = MaybeUninit::uninit();

/// What a flight did, for the exit status and the printed line.
struct Report {
    steps: u32,
    revolutions: u32,
    matches_accepted: u32,
    motors_finite: bool,
}

/// Builds the vehicle in its static slot; called once. Out of line, so that the temporary copy
/// of the state the constructors return lives in a frame that is gone before the flight.
#[inline(never)]
fn start() -> &'static mut Vehicle {
    let slot = &raw mut VEHICLE;
    let vehicle = Vehicle {
        decoder: Xv11Decoder::new(),
        onboard: Onboard::new(OdometryConfig::in_flight(), AutopilotConfig::default()),
    };
    // SAFETY: called once, from the entry, on the only thread, with no interrupts, so this is
    // the only reference to `VEHICLE` that ever exists.
    unsafe { (*slot).write(vehicle) }
}

/// Flies the capture through the stack: a level vehicle at rest, armed after 0.5 s.
#[inline(never)]
fn fly(vehicle: &mut Vehicle) -> Report {
    let mut report = Report {
        steps: 0,
        revolutions: 0,
        matches_accepted: 0,
        motors_finite: true,
    };
    // Through `black_box`, so the compiler cannot fold the capture or the sensor values into
    // the code: the image holds the code a live device would run.
    let mut bytes = black_box(CAPTURE);
    let mut t_s = 0.0f64;
    while !bytes.is_empty() {
        let chunk = &bytes[..bytes.len().min(BYTES_PER_STEP)];
        let (used, revolution) = vehicle.decoder.feed(chunk);
        bytes = &bytes[used..];
        let scan = revolution.map(|r| r.to_scan(t_s));
        report.revolutions += u32::from(scan.is_some());
        let inputs = black_box(Inputs {
            t_s,
            imu: ImuSample {
                t_s,
                gyro_rad_s: [0.0; 3],
                accel_m_s2: [0.0, 0.0, GRAVITY_M_S2],
            },
            sonar: None,
            scan_match: None,
            battery: None,
            pilot: PilotInput {
                arm: t_s > 0.5,
                ..PilotInput::default()
            },
            mission: None,
            companion: Default::default(),
            ground: Default::default(),
        });
        let outputs = vehicle.onboard.step(&inputs, scan.as_ref(), DT_S);
        report.motors_finite &= outputs.motors.throttle_norm.iter().all(|m| m.is_finite());
        black_box(outputs);
        report.steps += 1;
        t_s += f64::from(DT_S);
    }
    report.matches_accepted = vehicle
        .onboard
        .autopilot()
        .estimator_counters()
        .scan_match
        .accepted;
    report
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    os::exit(101)
}

/// The process around [`start`] and [`fly`] on x86-64 Linux: entry, exit, output and a stack gauge, by system
/// call, and the memory functions the compiler calls (there is no C library; a microcontroller
/// target's `compiler_builtins` has them).
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
mod os {
    use super::{fly, start, Report};
    use core::arch::{asm, naked_asm};
    use core::ops::Range;

    /// Stack below the entry's frame that is painted before each phase and checked after it (the
    /// kernel grows the main stack on demand).
    const STACK_GAUGE_BYTES: usize = 256 * 1024;
    /// Left unpainted just below the entry's frame (its red zone and the painting loop's own use).
    const GAUGE_GAP_BYTES: usize = 512;
    const PAINT: u64 = 0x5a5a_5a5a_5a5a_5a5a;

    /// The kernel enters with the stack 16-byte aligned; a called function expects it 8 bytes
    /// off (the return address), so align it and call, with the stack's top as the argument.
    #[unsafe(naked)]
    #[unsafe(no_mangle)]
    extern "C" fn _start() -> ! {
        naked_asm!(
            "xor ebp, ebp",
            "and rsp, -16",
            "mov rdi, rsp",
            "call {entry}",
            "ud2",
            entry = sym entry
        );
    }

    /// Starts and flies the vehicle and reports how deep each phase went below `top`: the
    /// entry's own frame counts whole, the rest as far as the paint below it was overwritten.
    extern "C" fn entry(top: usize) -> ! {
        let here: usize;
        // SAFETY: reads the stack pointer, nothing else.
        unsafe { asm!("mov {}, rsp", out(reg) here, options(nomem, nostack)) };
        let bottom = here - STACK_GAUGE_BYTES;
        let painted = bottom..here - GAUGE_GAP_BYTES;
        paint(painted.clone());
        let vehicle = start();
        let start_up = top - lowest_used(painted.clone());
        paint(painted.clone());
        let report = fly(vehicle);
        let flight = top - lowest_used(painted);
        print(&report, start_up, flight);
        let ok = report.revolutions >= 10 && report.matches_accepted > 0 && report.motors_finite;
        exit(if ok { 0 } else { 1 })
    }

    fn paint(range: Range<usize>) {
        for a in range.step_by(8) {
            // SAFETY: the main thread's stack below the entry's frame, which nothing else uses
            // while this runs; the kernel maps it on first touch.
            unsafe { (a as *mut u64).write_volatile(PAINT) };
        }
    }

    /// The lowest address in `range` whose paint was overwritten (its end if none was).
    fn lowest_used(range: Range<usize>) -> usize {
        let mut low = range.start;
        // SAFETY: the range `paint` wrote.
        while low < range.end && unsafe { (low as *const u64).read_volatile() } == PAINT {
            low += 8;
        }
        low
    }

    fn print(r: &Report, start_up_stack: usize, flight_stack: usize) {
        let mut line = Line::default();
        line.push(b"plumbline-bare: ");
        line.number(r.steps as usize);
        line.push(b" steps, ");
        line.number(r.revolutions as usize);
        line.push(b" revolutions, ");
        line.number(r.matches_accepted as usize);
        line.push(b" scan matches accepted, motors ");
        line.push(if r.motors_finite {
            b"finite"
        } else {
            b"NOT FINITE"
        });
        line.push(b"; stack: ");
        line.number(flight_stack);
        line.push(b" bytes in flight, ");
        line.number(start_up_stack);
        line.push(b" at start-up\n");
        write(&line.bytes[..line.len]);
    }

    /// A fixed buffer for the one line printed.
    struct Line {
        bytes: [u8; 200],
        len: usize,
    }

    impl Default for Line {
        fn default() -> Self {
            Self {
                bytes: [0; 200],
                len: 0,
            }
        }
    }

    impl Line {
        fn push(&mut self, s: &[u8]) {
            let n = s.len().min(self.bytes.len() - self.len);
            self.bytes[self.len..self.len + n].copy_from_slice(&s[..n]);
            self.len += n;
        }

        fn number(&mut self, mut v: usize) {
            let mut digits = [0u8; 20];
            let mut i = digits.len();
            loop {
                i -= 1;
                digits[i] = b'0' + (v % 10) as u8;
                v /= 10;
                if v == 0 {
                    break;
                }
            }
            self.push(&digits[i..]);
        }
    }

    fn write(bytes: &[u8]) {
        // SAFETY: write(2) to standard output from a valid buffer of that length.
        unsafe {
            asm!("syscall", inlateout("rax") 1usize => _, in("rdi") 1usize, in("rsi") bytes.as_ptr(),
                 in("rdx") bytes.len(), lateout("rcx") _, lateout("r11") _, options(nostack));
        }
    }

    pub fn exit(code: i32) -> ! {
        // SAFETY: exit_group(2) ends the process; it does not return.
        unsafe {
            asm!("syscall", in("rax") 231usize, in("rdi") code as usize, options(noreturn, nostack))
        }
    }

    /// # Safety
    /// `dest` and `src` valid for `n` bytes and not overlapping.
    #[unsafe(no_mangle)]
    unsafe extern "C" fn memcpy(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
        for i in 0..n {
            // SAFETY: within the `n` bytes the caller vouches for.
            unsafe { *dest.add(i) = *src.add(i) };
        }
        dest
    }

    /// # Safety
    /// `dest` and `src` valid for `n` bytes; they may overlap.
    #[unsafe(no_mangle)]
    unsafe extern "C" fn memmove(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
        if (dest as usize) < (src as usize) {
            for i in 0..n {
                // SAFETY: as above; copying upwards never overwrites a byte still to be read.
                unsafe { *dest.add(i) = *src.add(i) };
            }
        } else {
            for i in (0..n).rev() {
                // SAFETY: as above; copying downwards never overwrites a byte still to be read.
                unsafe { *dest.add(i) = *src.add(i) };
            }
        }
        dest
    }

    /// # Safety
    /// `dest` valid for `n` bytes.
    #[unsafe(no_mangle)]
    unsafe extern "C" fn memset(dest: *mut u8, byte: i32, n: usize) -> *mut u8 {
        for i in 0..n {
            // SAFETY: within the `n` bytes the caller vouches for.
            unsafe { *dest.add(i) = byte as u8 };
        }
        dest
    }
}
