#![cfg_attr(target_arch = "avr", no_std, no_main)]
#![cfg_attr(target_arch = "avr", feature(abi_avr_interrupt))]

#[cfg(not(target_arch = "avr"))]
fn main() {}

#[cfg(target_arch = "avr")]
use panic_halt as _;

#[cfg(target_arch = "avr")]
#[avr_device::entry]
fn main() -> ! {
    let dp = avr_device::atmega328p::Peripherals::take().unwrap();
    dp.PORTB.ddrb().write(|w| unsafe { w.bits(0x20) });
    loop {
        dp.PORTB.portb().write(|w| unsafe { w.bits(0x20) });
    }
}
