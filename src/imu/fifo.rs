//! ICM-42688-P FIFO path: every sample at the chip's ODR, integrated into
//! the monitor period (no point sampling, no aliasing by the task's rate).
//!
//! [`Icm42688Fifo`] wraps the register driver [`Icm42688`], puts the chip's
//! FIFO in stop-on-full mode with packet 3 (TDK DS-000347 rev 1.8, §6:
//! header, accelerometer, gyro, 8-bit temperature, 16-bit ODR time stamp:
//! 16 bytes) and a watermark of one monitor period, and on every
//! [`Imu::read`] reads `INT_STATUS` + `FIFO_COUNT` and the packets in two
//! bursts, parses them, and integrates them with coning and sculling
//! corrections ([`DeltaIntegrator`]). The sample it returns is the period's
//! average rate `Δθ/T` and specific force `Δv/T`.
//!
//! Nothing is dropped in silence: an overflow (`FIFO_FULL_INT`, or a count
//! at capacity) sets [`FifoStatus::overflowed`]; packets that never reached
//! the FIFO are counted from the gaps in the chip's time stamps
//! ([`FifoStatus::packets_lost`]) and, for every whole monitor period they
//! span, advance [`ImuSample::sequence`], so
//! [`MonitorTask`](crate::monitor::MonitorTask) counts them in
//! `missed_samples`; the period's average is taken over the samples that
//! exist, and `timestamp_us` (chip time) spans the gap. Packets with the
//! chip's "no data" value or a malformed header are counted
//! ([`FifoStatus::invalid_packets`]); a malformed header (the byte stream
//! lost its packet alignment) flushes the FIFO and re-synchronises.

use embedded_hal::spi::SpiDevice;

use super::icm42688::{reg, Error, Icm42688, NO_DATA};
use super::integrate::DeltaIntegrator;
use super::{Imu, ImuSample};

/// Bytes of one packet 3 (header, accel, gyro, temperature, time stamp).
pub const PACKET_LEN: usize = 16;
/// FIFO size, bytes (DS-000347 §6.1: 2 KB).
pub const FIFO_BYTES: usize = 2048;
/// Packets 3 the FIFO holds.
pub const FIFO_PACKETS: usize = FIFO_BYTES / PACKET_LEN;
/// Resolution of the packets' time stamps with `TMST_RES` = 1, µs.
pub const TIMESTAMP_RES_US: u32 = 16;

/// FIFO packet header bits (DS-000347 §6.2).
pub mod header {
    /// 1: the FIFO is empty (nothing valid follows).
    pub const MSG: u8 = 0x80;
    /// The packet has room for accelerometer data.
    pub const ACCEL: u8 = 0x40;
    /// The packet has room for gyro data.
    pub const GYRO: u8 = 0x20;
    /// 20-bit (packet 4) data.
    pub const HIRES_20: u8 = 0x10;
    /// Time-stamp field (bits 3:2); `0b10`: ODR time stamp.
    pub const TMST_MASK: u8 = 0x0C;
    /// ODR time stamp in the time-stamp field.
    pub const TMST_ODR: u8 = 0x08;
    /// The header of a packet 3 (the ODR-change bits 1:0 aside).
    pub const PACKET3: u8 = ACCEL | GYRO | TMST_ODR;
}

/// `INT_STATUS` bits.
pub mod int_status {
    /// A sample was written to the data registers.
    pub const DATA_RDY: u8 = 0x08;
    /// The FIFO count reached the watermark.
    pub const FIFO_THS: u8 = 0x04;
    /// The FIFO filled up (stop-on-full: samples were dropped).
    pub const FIFO_FULL: u8 = 0x02;
}

/// One packet 3 as stored, in counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawPacket {
    /// Accelerometer x, y, z.
    pub accel: [i16; 3],
    /// Gyro x, y, z.
    pub gyro: [i16; 3],
    /// Temperature, 8 bit (`T = t / 2.07 + 25` °C).
    pub temperature: i8,
    /// ODR time stamp (wraps).
    pub timestamp: u16,
}

/// What one 16-byte slot of the FIFO holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Packet {
    /// A valid accelerometer + gyro sample.
    Sample(RawPacket),
    /// A packet whose accelerometer or gyro holds the "no data" value
    /// (−32768: sensor off or not settled); its time stamp is valid.
    NoData {
        /// ODR time stamp.
        timestamp: u16,
    },
    /// The header says the FIFO is empty.
    Empty,
    /// A header that is not packet 3 (misaligned read, other packet type).
    Malformed(u8),
}

/// Parses one packet 3 (big-endian data, the chip's default).
pub fn parse_packet(p: &[u8; PACKET_LEN]) -> Packet {
    let [h, ax1, ax0, ay1, ay0, az1, az0, gx1, gx0, gy1, gy0, gz1, gz0, t, ts1, ts0] = *p;
    if h & header::MSG != 0 {
        return Packet::Empty;
    }
    // The ODR-change bits (1:0) may be set on any packet.
    if h & 0xFC != header::PACKET3 {
        return Packet::Malformed(h);
    }
    let w = i16::from_be_bytes;
    let accel = [w([ax1, ax0]), w([ay1, ay0]), w([az1, az0])];
    let gyro = [w([gx1, gx0]), w([gy1, gy0]), w([gz1, gz0])];
    let timestamp = u16::from_be_bytes([ts1, ts0]);
    if accel.iter().chain(gyro.iter()).any(|&x| x == NO_DATA) {
        return Packet::NoData { timestamp };
    }
    Packet::Sample(RawPacket {
        accel,
        gyro,
        temperature: i8::from_be_bytes([t]),
        timestamp,
    })
}

/// What the last [`Imu::read`] found in the FIFO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoStatus {
    /// Packets the chip said it held (`FIFO_COUNT`, in records).
    pub count: u16,
    /// Packets read this time.
    pub packets_read: u16,
    /// Samples integrated into the returned average.
    pub samples: u16,
    /// The FIFO had filled up (`FIFO_FULL_INT`, or `FIFO_COUNT` at
    /// capacity): in stop-on-full mode the chip dropped samples.
    pub overflowed: bool,
    /// `FIFO_THS_INT`: the count had reached the watermark.
    pub watermark_reached: bool,
    /// Samples missing from the chip's time-stamp sequence since the
    /// previous packet read (dropped on overflow). Counted modulo the
    /// time stamp's wrap (2¹⁶ × 16 µs ≈ 1.05 s): a longer stall is
    /// under-counted, but `overflowed` is set.
    pub packets_lost: u32,
    /// Packets with the "no data" value, an empty marker or a malformed
    /// header.
    pub invalid_packets: u16,
    /// A malformed header made the driver flush the FIFO.
    pub resynchronised: bool,
}

/// Counters since the driver started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoTotals {
    /// Reads that found the FIFO overflowed.
    pub overflows: u32,
    /// Samples lost (see [`FifoStatus::packets_lost`]).
    pub packets_lost: u32,
    /// Invalid packets.
    pub invalid_packets: u32,
    /// FIFO flushes to re-synchronise.
    pub resyncs: u32,
}

/// The ICM-42688-P read through its FIFO at full ODR, integrated over the
/// monitor period. The FIFO is read in bursts of up to `N` packets (16
/// bytes each, held in the driver), as many as it takes to empty it.
#[derive(Debug)]
pub struct Icm42688Fifo<SPI, const N: usize = 32> {
    dev: Icm42688<SPI>,
    buf: [[u8; PACKET_LEN]; N],
    integrator: DeltaIntegrator,
    watermark: u16,
    period_us: u32,
    last_timestamp: Option<u16>,
    time_us: u32,
    sequence: u32,
    temperature: f32,
    /// `INT_STATUS` flags read (and so cleared on the chip) by a read whose
    /// data burst then failed: reported by the next read.
    pending_flags: u8,
    status: FifoStatus,
    totals: FifoTotals,
}

/// `FIFO_CONFIG`: stop-on-full mode (bits 7:6 = 11, as PX4's driver).
const FIFO_MODE_STOP_ON_FULL: u8 = 0xC0;
/// `FIFO_CONFIG1`: watermark when count ≥ threshold, ODR time stamp,
/// temperature, gyro, accelerometer: packet 3.
const FIFO_CONFIG1_PACKET3: u8 = 0x2F;
/// `INTF_CONFIG0`: count in records, big-endian count and data, SPI only.
const INTF_CONFIG0_RECORDS: u8 = 0x73;
/// `TMST_CONFIG`: `TMST_EN` and `TMST_RES` (16 µs).
const TMST_EN_RES16: u8 = 0x09;
/// `TMST_CONFIG`: `TMST_DELTA_EN` (must be off: absolute time stamps).
const TMST_DELTA: u8 = 0x04;
/// `SIGNAL_PATH_RESET`: `FIFO_FLUSH`.
const FIFO_FLUSH: u8 = 0x02;

impl<SPI: SpiDevice, const N: usize> Icm42688Fifo<SPI, N> {
    /// Configures the FIFO of an initialised chip: packet 3, count in
    /// records, 16 µs time stamps, stop-on-full, watermark of
    /// `period_samples` packets (the ODR samples in one monitor period,
    /// e.g. 20 at 1 kHz for a 50 Hz monitor; clamped to 1…[`FIFO_PACKETS`]),
    /// then flushes it.
    pub fn new(mut dev: Icm42688<SPI>, period_samples: u16) -> Result<Self, Error<SPI::Error>> {
        let wm = period_samples.clamp(1, FIFO_PACKETS as u16);
        dev.write_register(reg::INTF_CONFIG0, INTF_CONFIG0_RECORDS)?;
        let tmst = dev.read_register(reg::TMST_CONFIG)?;
        dev.write_register(reg::TMST_CONFIG, (tmst | TMST_EN_RES16) & !TMST_DELTA)?;
        dev.write_register(reg::FIFO_CONFIG1, FIFO_CONFIG1_PACKET3)?;
        let [wm_hi, wm_lo] = wm.to_be_bytes();
        dev.write_register(reg::FIFO_CONFIG2, wm_lo)?;
        dev.write_register(reg::FIFO_CONFIG3, wm_hi & 0x0F)?;
        dev.write_register(reg::FIFO_CONFIG, FIFO_MODE_STOP_ON_FULL)?;
        dev.write_register(reg::SIGNAL_PATH_RESET, FIFO_FLUSH)?;
        let period_us = dev.config().odr.period_us();
        Ok(Self {
            dev,
            buf: [[0; PACKET_LEN]; N],
            integrator: DeltaIntegrator::new(),
            watermark: wm,
            period_us,
            last_timestamp: None,
            time_us: 0,
            sequence: 0,
            temperature: 25.0,
            pending_flags: 0,
            status: FifoStatus::default(),
            totals: FifoTotals::default(),
        })
    }

    /// What the last read found.
    pub fn fifo_status(&self) -> &FifoStatus {
        &self.status
    }

    /// Counters since start.
    pub fn fifo_totals(&self) -> &FifoTotals {
        &self.totals
    }

    /// The watermark in use, packets.
    pub fn watermark(&self) -> u16 {
        self.watermark
    }

    /// The register driver (configuration, registers).
    pub fn device(&mut self) -> &mut Icm42688<SPI> {
        &mut self.dev
    }

    /// Releases the register driver.
    pub fn destroy(self) -> Icm42688<SPI> {
        self.dev
    }

    /// Moves the driver's time to the packet stamped `ts`: returns the ODR
    /// periods since the previous packet (≥ 1) and counts the missing ones.
    fn advance(&mut self, ts: u16, st: &mut FifoStatus) -> u32 {
        let k = self.periods_since(ts);
        st.packets_lost = st.packets_lost.saturating_add(k - 1);
        self.last_timestamp = Some(ts);
        self.time_us = self.time_us.wrapping_add(k.saturating_mul(self.period_us));
        k
    }

    /// ODR periods from the previous time stamp to `ts` (≥ 1).
    fn periods_since(&self, ts: u16) -> u32 {
        let Some(prev) = self.last_timestamp else {
            return 1;
        };
        let dt_us = u32::from(ts.wrapping_sub(prev)) * TIMESTAMP_RES_US;
        // Rounded to whole periods: the 16 µs stamps of a 1 kHz ODR step
        // by 62 or 63 ticks.
        ((dt_us + self.period_us / 2) / self.period_us.max(1)).max(1)
    }

    /// Reads and integrates what the FIFO holds; the status of this read.
    fn drain(&mut self) -> Result<FifoStatus, Error<SPI::Error>> {
        let mut st = FifoStatus::default();
        let mut head = [0u8; 3];
        self.dev.read_registers(reg::INT_STATUS, &mut head)?;
        let [flags, count_hi, count_lo] = head;
        let flags = flags | core::mem::take(&mut self.pending_flags);
        let count = u16::from_be_bytes([count_hi, count_lo]);
        st.count = count;
        st.overflowed = flags & int_status::FIFO_FULL != 0 || usize::from(count) >= FIFO_PACKETS;
        st.watermark_reached = flags & int_status::FIFO_THS != 0;
        let (alsb, glsb) = (self.dev.accel_lsb(), self.dev.gyro_lsb());
        let mut malformed = false;
        // Everything the count says is there, in bursts of up to N packets
        // (so a stall that filled the FIFO is drained in one call).
        let mut remaining = usize::from(count).min(FIFO_PACKETS);
        while remaining > 0 && !malformed {
            let n = remaining.min(N.max(1));
            remaining -= n;
            let Some(packets) = self.buf.get_mut(..n) else {
                break;
            };
            if let Err(e) = self
                .dev
                .read_registers(reg::FIFO_DATA, packets.as_flattened_mut())
            {
                self.pending_flags = flags;
                return Err(e);
            }
            for i in 0..n {
                let Some(p) = self.buf.get(i) else { break };
                st.packets_read = st.packets_read.saturating_add(1);
                match parse_packet(p) {
                    Packet::Sample(raw) => {
                        let k = self.advance(raw.timestamp, &mut st);
                        let h = k.saturating_mul(self.period_us) as f32 * 1e-6;
                        let g = raw.gyro.map(|c| f32::from(c) * glsb);
                        let a = raw.accel.map(|c| f32::from(c) * alsb);
                        if self.integrator.push(g, a, h) {
                            st.samples = st.samples.saturating_add(1);
                        }
                        self.temperature = f32::from(raw.temperature) / 2.07 + 25.0;
                    }
                    Packet::NoData { timestamp } => {
                        self.advance(timestamp, &mut st);
                        st.invalid_packets = st.invalid_packets.saturating_add(1);
                    }
                    // An empty marker inside the counted packets, or a header
                    // that is not packet 3: the stream lost its alignment.
                    Packet::Empty | Packet::Malformed(_) => {
                        st.invalid_packets = st.invalid_packets.saturating_add(1);
                        malformed = true;
                        break;
                    }
                }
            }
        }
        if malformed {
            // The rest of the stream cannot be trusted to be aligned.
            self.dev
                .write_register(reg::SIGNAL_PATH_RESET, FIFO_FLUSH)?;
            st.resynchronised = true;
            self.last_timestamp = None;
        }
        Ok(st)
    }
}

impl<SPI: SpiDevice, const N: usize> Imu for Icm42688Fifo<SPI, N> {
    type Error = Error<SPI::Error>;

    /// Drains the FIFO and returns the average rate and specific force
    /// over the samples read (see the module docs). [`Error::NoData`] when
    /// the FIFO held no valid sample; [`Error::Spi`] on a bus error (what
    /// was already integrated is kept for the next read).
    fn read(&mut self) -> Result<ImuSample, Self::Error> {
        let st = self.drain()?;
        let t = &mut self.totals;
        t.overflows = t.overflows.saturating_add(u32::from(st.overflowed));
        t.packets_lost = t.packets_lost.saturating_add(st.packets_lost);
        t.invalid_packets = t
            .invalid_packets
            .saturating_add(u32::from(st.invalid_packets));
        t.resyncs = t.resyncs.saturating_add(u32::from(st.resynchronised));
        self.status = st;
        let Some(d) = self.integrator.take() else {
            return Err(Error::NoData);
        };
        // Whole monitor periods the lost samples span count as missed
        // periods for the task.
        let missed = st.packets_lost / u32::from(self.watermark.max(1));
        self.sequence = self.sequence.wrapping_add(missed);
        let s = ImuSample {
            accel: d.mean_specific_force(),
            gyro: d.mean_rate(),
            temperature: self.temperature,
            sequence: self.sequence,
            timestamp_us: Some(self.time_us),
        };
        self.sequence = self.sequence.wrapping_add(1);
        Ok(s)
    }
}
