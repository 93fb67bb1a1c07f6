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
//!
//! The FIFO (DS-000347 §6) is emulated for packet 3 (header 0x68,
//! accelerometer, gyro, 8-bit temperature, 16-bit ODR time stamp; 16 bytes)
//! in a 2 KB buffer: [`EmulatedIcm42688::sample_odr`] presents one sample
//! at the output data rate and, unless `FIFO_CONFIG` is in bypass, appends
//! its packet. Stream-to-FIFO mode drops the oldest packet when full,
//! stop-on-full drops the new one; both set `FIFO_FULL_INT`, and the
//! dropped packets are counted ([`EmulatedIcm42688::fifo_dropped`], the
//! ground truth a driver's loss count is checked against). `FIFO_COUNT`
//! counts bytes or records (`INTF_CONFIG0.FIFO_COUNT_REC`) in either byte
//! order, `FIFO_THS_INT` follows the watermark (`FIFO_CONFIG2/3`),
//! `INT_STATUS` clears on read, `FIFO_DATA` pops a byte per read without
//! advancing the address (0xFF when empty), `SIGNAL_PATH_RESET.FIFO_FLUSH`
//! empties it. Time stamps count the chip's own ODR ticks at 1 µs or 16 µs
//! (`TMST_CONFIG.TMST_RES`). Not emulated: packets 1, 2 and 4 (other
//! `FIFO_CONFIG1` contents put nothing in the FIFO), little-endian sensor
//! data, partial-read resume.

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

use imu_fdi::imu::fifo::{header, int_status, FIFO_BYTES, PACKET_LEN};
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
    fifo: [u8; FIFO_BYTES],
    fifo_head: usize,
    fifo_len: usize,
    fifo_dropped: u64,
    odr_ticks: u64,
    int_flags: u8,
    count_latch: u16,
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
            fifo: [0; FIFO_BYTES],
            fifo_head: 0,
            fifo_len: 0,
            fifo_dropped: 0,
            odr_ticks: 0,
            int_flags: 0,
            count_latch: 0,
        };
        c.reset();
        c
    }

    fn reset(&mut self) {
        self.regs = [0; REGS];
        self.set(reg::WHO_AM_I, DEVICE_ID);
        // Reset values: ±2000 °/s, ±16 g, 1 kHz; sensors off; FIFO in
        // bypass; big-endian count and data; time stamps on at 1 µs.
        self.set(reg::GYRO_CONFIG0, 0x06);
        self.set(reg::ACCEL_CONFIG0, 0x06);
        self.set(reg::GYRO_ACCEL_CONFIG0, 0x11);
        self.set(reg::INTF_CONFIG0, 0x30);
        self.set(reg::TMST_CONFIG, 0x23);
        self.flush_fifo();
        self.int_flags = 0;
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

    /// One sample at the output data rate: presents it in the data
    /// registers (as [`set_sample`](Self::set_sample)), advances the chip's
    /// time stamp by one ODR period, raises `DATA_RDY_INT` and, unless the
    /// FIFO is in bypass, appends its packet 3.
    pub fn sample_odr(&mut self, accel_mps2: [f64; 3], gyro_rads: [f64; 3], temperature_c: f64) {
        self.sample = Some((accel_mps2, gyro_rads, temperature_c));
        self.refresh();
        self.odr_ticks = self.odr_ticks.wrapping_add(1);
        self.int_flags |= int_status::DATA_RDY;
        self.push_packet();
    }

    /// Packets (or their oldest bytes, in stream mode) the FIFO dropped
    /// because it was full, since power-on.
    pub fn fifo_dropped(&self) -> u64 {
        self.fifo_dropped
    }

    /// Bytes in the FIFO.
    pub fn fifo_bytes(&self) -> usize {
        self.fifo_len
    }

    /// ODR period of the gyro's `GYRO_ODR` code, µs (0 for a code this
    /// emulator does not know).
    fn odr_period_us(&self) -> f64 {
        match self.get(reg::GYRO_CONFIG0) & 0x0F {
            0b0001 => 1e6 / 32_000.0,
            0b0010 => 1e6 / 16_000.0,
            0b0011 => 125.0,
            0b0100 => 250.0,
            0b0101 => 500.0,
            0b0110 => 1_000.0,
            0b0111 => 5_000.0,
            0b1000 => 10_000.0,
            0b1001 => 20_000.0,
            0b1111 => 2_000.0,
            _ => 0.0,
        }
    }

    fn flush_fifo(&mut self) {
        self.fifo_head = 0;
        self.fifo_len = 0;
    }

    fn fifo_push_byte(&mut self, b: u8) {
        let i = (self.fifo_head + self.fifo_len) % FIFO_BYTES;
        if let Some(x) = self.fifo.get_mut(i) {
            *x = b;
        }
        self.fifo_len += 1;
    }

    fn fifo_pop_byte(&mut self) -> u8 {
        if self.fifo_len == 0 {
            return 0xFF;
        }
        let b = self.fifo.get(self.fifo_head).copied().unwrap_or(0xFF);
        self.fifo_head = (self.fifo_head + 1) % FIFO_BYTES;
        self.fifo_len -= 1;
        b
    }

    /// The FIFO count as the chip reports it: records or bytes.
    fn fifo_count(&self) -> u16 {
        let records = self.get(reg::INTF_CONFIG0) & 0x40 != 0;
        let n = if records {
            self.fifo_len / PACKET_LEN
        } else {
            self.fifo_len
        };
        n as u16
    }

    fn push_packet(&mut self) {
        let mode = self.get(reg::FIFO_CONFIG) >> 6;
        // Packet 3 only: accel, gyro, temperature and time stamp enabled.
        if mode == 0 || self.get(reg::FIFO_CONFIG1) & 0x0F != 0x0F {
            return;
        }
        if self.fifo_len + PACKET_LEN > FIFO_BYTES {
            self.int_flags |= int_status::FIFO_FULL;
            self.fifo_dropped += 1;
            if mode == 0b01 {
                // Stream-to-FIFO: the oldest packet makes room.
                for _ in 0..PACKET_LEN {
                    self.fifo_pop_byte();
                }
            } else {
                // Stop-on-full: the new sample is lost.
                return;
            }
        }
        let res_us = if self.get(reg::TMST_CONFIG) & 0x08 != 0 {
            16.0
        } else {
            1.0
        };
        let t_us = self.odr_ticks as f64 * self.odr_period_us();
        let ts = (libm::floor(t_us / res_us) as u64 & 0xFFFF) as u16;
        let data = |chip: &Self, addr: u8| -> [u8; 2] { [chip.get(addr), chip.get(addr + 1)] };
        let mut p = [0u8; PACKET_LEN];
        p[0] = header::PACKET3;
        for i in 0..6u8 {
            let [hi, lo] = data(self, reg::TEMP_DATA1 + 2 + 2 * i);
            p[1 + 2 * usize::from(i)] = hi;
            p[2 + 2 * usize::from(i)] = lo;
        }
        // FIFO temperature: 8 bit, T = t / 2.07 + 25 °C.
        let temp = self.sample.map_or(25.0, |s| s.2);
        p[13] = (libm::round((temp - 25.0) * 2.07).clamp(-128.0, 127.0) as i8) as u8;
        let [t1, t0] = ts.to_be_bytes();
        p[14] = t1;
        p[15] = t0;
        for b in p {
            self.fifo_push_byte(b);
        }
        if self.fifo_len + PACKET_LEN > FIFO_BYTES {
            self.int_flags |= int_status::FIFO_FULL;
        }
        let wm = u16::from(self.get(reg::FIFO_CONFIG2))
            | (u16::from(self.get(reg::FIFO_CONFIG3) & 0x0F) << 8);
        if wm > 0 && self.fifo_count() >= wm {
            self.int_flags |= int_status::FIFO_THS;
        }
    }

    /// A register read with the chip's side effects.
    fn read_byte(&mut self, addr: u8) -> u8 {
        let big = self.get(reg::INTF_CONFIG0) & 0x20 != 0;
        match addr {
            reg::INT_STATUS => core::mem::take(&mut self.int_flags),
            reg::FIFO_COUNTH => {
                self.count_latch = self.fifo_count();
                let [hi, lo] = self.count_latch.to_be_bytes();
                if big {
                    hi
                } else {
                    lo
                }
            }
            reg::FIFO_COUNTL => {
                let [hi, lo] = self.count_latch.to_be_bytes();
                if big {
                    lo
                } else {
                    hi
                }
            }
            reg::FIFO_DATA => self.fifo_pop_byte(),
            a => self.get(a),
        }
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
            reg::SIGNAL_PATH_RESET => {
                // FIFO_FLUSH (bit 1) empties the FIFO; the bit self-clears.
                if v & 0x02 != 0 {
                    self.flush_fifo();
                }
                self.set(addr, v & !0x02);
            }
            reg::FIFO_CONFIG => {
                if v >> 6 == 0 {
                    // Bypass: the FIFO is not in use.
                    self.flush_fifo();
                }
                self.set(addr, v);
            }
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
                        let out = if *reading { chip.read_byte(*a) } else { 0 };
                        if !*reading {
                            chip.write_register(*a, byte_in);
                        }
                        // Reads of FIFO_DATA keep popping the FIFO.
                        if !(*reading && *a == reg::FIFO_DATA) {
                            *a = a.wrapping_add(1) & 0x7F;
                        }
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
