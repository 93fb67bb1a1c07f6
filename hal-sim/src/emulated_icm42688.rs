//! A register-level ICM-42688-P behind `embedded_hal::spi::SpiDevice`.
//!
//! It answers the SPI protocol of the real chip (address byte with the read
//! flag 0x80, auto-incrementing register address, writes of any length),
//! holds the bank-0 registers the driver uses with their reset values,
//! performs the soft reset, reports the "no data" value (−32768) until the
//! sensors are switched on in `PWR_MGMT0`, and converts samples given in SI
//! units into big-endian counts at the configured full scale, with rounding
//! and saturation. Bus failures can be injected. `no_std`, so the same
//! emulated chip runs on the host and inside the QEMU firmware.

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

use imu_fdi::imu::icm42688::{reg, DEVICE_ID, NO_DATA};

const REGS: usize = 128;
const DEG: f64 = core::f64::consts::PI / 180.0;
const G0: f64 = 9.806_65;

/// Error of the emulated bus (only when injected).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmulatedBusError;

impl embedded_hal::spi::Error for EmulatedBusError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// The emulated chip.
#[derive(Debug, Clone)]
pub struct EmulatedIcm42688 {
    regs: [u8; REGS],
    fail_next: u32,
    transactions: u32,
    sample: Option<([f64; 3], [f64; 3], f64)>,
}

impl Default for EmulatedIcm42688 {
    fn default() -> Self {
        Self::new()
    }
}

impl EmulatedIcm42688 {
    /// A chip in its power-on state.
    pub fn new() -> Self {
        let mut c = Self {
            regs: [0; REGS],
            fail_next: 0,
            transactions: 0,
            sample: None,
        };
        c.reset();
        c
    }

    fn reset(&mut self) {
        self.regs = [0; REGS];
        self.set(reg::WHO_AM_I, DEVICE_ID);
        // Reset values: ±2000 °/s, ±16 g, 1 kHz; sensors off.
        self.set(reg::GYRO_CONFIG0, 0x06);
        self.set(reg::ACCEL_CONFIG0, 0x06);
        self.set(reg::GYRO_ACCEL_CONFIG0, 0x11);
        self.refresh();
    }

    fn get(&self, addr: u8) -> u8 {
        self.regs
            .get(usize::from(addr & 0x7F))
            .copied()
            .unwrap_or(0)
    }

    fn set(&mut self, addr: u8, v: u8) {
        if let Some(r) = self.regs.get_mut(usize::from(addr & 0x7F)) {
            *r = v;
        }
    }

    /// Presents a new sample (sensor axes, SI units) in the data registers.
    pub fn set_sample(&mut self, accel_mps2: [f64; 3], gyro_rads: [f64; 3], temperature_c: f64) {
        self.sample = Some((accel_mps2, gyro_rads, temperature_c));
        self.refresh();
    }

    /// Makes the next `n` transactions fail.
    pub fn fail_next(&mut self, n: u32) {
        self.fail_next = n;
    }

    /// Transactions served so far (including failed ones).
    pub fn transactions(&self) -> u32 {
        self.transactions
    }

    fn accel_fs_g(&self) -> f64 {
        16.0 / f64::from(1u8 << ((self.get(reg::ACCEL_CONFIG0) >> 5) & 0x3))
    }

    fn gyro_fs_dps(&self) -> f64 {
        2000.0 / f64::from(1u8 << ((self.get(reg::GYRO_CONFIG0) >> 5) & 0x7).min(7))
    }

    fn write_word(&mut self, addr: u8, w: i16) {
        let [hi, lo] = w.to_be_bytes();
        self.set(addr, hi);
        self.set(addr + 1, lo);
    }

    /// Rewrites the data registers from the current sample and configuration.
    fn refresh(&mut self) {
        let pwr = self.get(reg::PWR_MGMT0);
        let accel_on = pwr & 0b11 != 0;
        let gyro_on = pwr & 0b1100 != 0;
        let counts = |v: f64, lsb: f64| -> i16 {
            let c = libm::round(v / lsb);
            // The chip saturates at ±32767; −32768 is reserved for "no data".
            c.clamp(-32767.0, 32767.0) as i16
        };
        let (accel, gyro, temp) = self.sample.unwrap_or(([0.0; 3], [0.0; 3], 25.0));
        let alsb = self.accel_fs_g() * G0 / 32768.0;
        let glsb = self.gyro_fs_dps() * DEG / 32768.0;
        let t = counts(temp - 25.0, 1.0 / 132.48);
        self.write_word(reg::TEMP_DATA1, t);
        for (i, v) in accel.iter().enumerate() {
            let w = if accel_on && self.sample.is_some() {
                counts(*v, alsb)
            } else {
                NO_DATA
            };
            self.write_word(reg::TEMP_DATA1 + 2 + 2 * i as u8, w);
        }
        for (i, v) in gyro.iter().enumerate() {
            let w = if gyro_on && self.sample.is_some() {
                counts(*v, glsb)
            } else {
                NO_DATA
            };
            self.write_word(reg::TEMP_DATA1 + 8 + 2 * i as u8, w);
        }
    }

    fn write_register(&mut self, addr: u8, v: u8) {
        match addr {
            reg::WHO_AM_I => {} // read-only
            reg::DEVICE_CONFIG if v & 1 != 0 => self.reset(),
            _ => {
                self.set(addr, v);
                self.refresh();
            }
        }
    }
}

impl ErrorType for EmulatedIcm42688 {
    type Error = EmulatedBusError;
}

impl SpiDevice for EmulatedIcm42688 {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        self.transactions = self.transactions.wrapping_add(1);
        if self.fail_next > 0 {
            self.fail_next -= 1;
            return Err(EmulatedBusError);
        }
        // The first byte clocked in is the address; the rest auto-increment.
        let mut addr: Option<u8> = None;
        let mut reading = false;
        let next_out =
            |chip: &mut Self, addr: &mut Option<u8>, reading: &mut bool, byte_in: u8| -> u8 {
                match addr {
                    None => {
                        *addr = Some(byte_in & 0x7F);
                        *reading = byte_in & 0x80 != 0;
                        0
                    }
                    Some(a) => {
                        let out = if *reading { chip.get(*a) } else { 0 };
                        if !*reading {
                            chip.write_register(*a, byte_in);
                        }
                        *a = a.wrapping_add(1) & 0x7F;
                        out
                    }
                }
            };
        for op in operations.iter_mut() {
            match op {
                Operation::Write(bytes) => {
                    for b in bytes.iter() {
                        next_out(self, &mut addr, &mut reading, *b);
                    }
                }
                Operation::Read(buf) => {
                    for x in buf.iter_mut() {
                        *x = next_out(self, &mut addr, &mut reading, 0);
                    }
                }
                Operation::Transfer(read, write) => {
                    let n = read.len().max(write.len());
                    for i in 0..n {
                        let out = next_out(
                            self,
                            &mut addr,
                            &mut reading,
                            write.get(i).copied().unwrap_or(0),
                        );
                        if let Some(r) = read.get_mut(i) {
                            *r = out;
                        }
                    }
                }
                Operation::TransferInPlace(buf) => {
                    for x in buf.iter_mut() {
                        *x = next_out(self, &mut addr, &mut reading, *x);
                    }
                }
                Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}

/// A handle that lets a driver own "the bus" while the simulation keeps
/// feeding samples into the same emulated chip (single-threaded, as on the MCU).
#[derive(Debug, Clone, Copy)]
pub struct SharedBus<'a>(pub &'a core::cell::RefCell<EmulatedIcm42688>);

impl ErrorType for SharedBus<'_> {
    type Error = EmulatedBusError;
}

impl SpiDevice for SharedBus<'_> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        // A re-entrant borrow cannot happen in this single-threaded use; report
        // it as a bus error rather than panicking if it ever did.
        match self.0.try_borrow_mut() {
            Ok(mut chip) => chip.transaction(operations),
            Err(_) => Err(EmulatedBusError),
        }
    }
}
