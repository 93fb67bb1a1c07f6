//! TDK InvenSense ICM-42688-P driver over [`SpiDevice`].
//!
//! * identity check (`WHO_AM_I` = 0x47), soft reset, low-noise mode,
//!   full scale, output data rate and UI filter bandwidth;
//! * the whole sample (temperature, accelerometer, gyro: 14 bytes from
//!   `TEMP_DATA1`) in one SPI transaction, so it cannot tear;
//! * big-endian two's complement scaling, the chip's "no data" value
//!   (−32768) reported as [`Error::NoData`], bus errors as [`Error::Spi`].

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use super::{Imu, ImuSample};

/// Register addresses (user bank 0).
pub mod reg {
    /// Soft reset (bit 0).
    pub const DEVICE_CONFIG: u8 = 0x11;
    /// FIFO mode (bits 7:6: 00 bypass, 01 stream-to-FIFO, 1x stop-on-full).
    pub const FIFO_CONFIG: u8 = 0x16;
    /// First data register: temperature high byte; 14 bytes to `GYRO_DATA_Z0`.
    pub const TEMP_DATA1: u8 = 0x1D;
    /// Interrupt status (clear on read): `FIFO_THS_INT` bit 2,
    /// `FIFO_FULL_INT` bit 1, `DATA_RDY_INT` bit 3.
    pub const INT_STATUS: u8 = 0x2D;
    /// FIFO count, high byte (the low byte follows at 0x2F).
    pub const FIFO_COUNTH: u8 = 0x2E;
    /// FIFO count, low byte.
    pub const FIFO_COUNTL: u8 = 0x2F;
    /// FIFO read port (the address does not auto-increment on it).
    pub const FIFO_DATA: u8 = 0x30;
    /// `FIFO_FLUSH` (bit 1).
    pub const SIGNAL_PATH_RESET: u8 = 0x4B;
    /// Interface: `FIFO_COUNT_REC` (bit 6), `FIFO_COUNT_ENDIAN` (bit 5),
    /// `SENSOR_DATA_ENDIAN` (bit 4), `UI_SIFS_CFG` (bits 1:0).
    pub const INTF_CONFIG0: u8 = 0x4C;
    /// Power management: gyro and accelerometer modes.
    pub const PWR_MGMT0: u8 = 0x4E;
    /// Gyro full scale (bits 7:5) and output data rate (bits 3:0).
    pub const GYRO_CONFIG0: u8 = 0x4F;
    /// Accelerometer full scale (bits 7:5) and output data rate (bits 3:0).
    pub const ACCEL_CONFIG0: u8 = 0x50;
    /// UI filter bandwidths: accelerometer (7:4), gyro (3:0).
    pub const GYRO_ACCEL_CONFIG0: u8 = 0x52;
    /// Time stamp: `TMST_RES` (bit 3, 16 µs), `TMST_EN` (bit 0).
    pub const TMST_CONFIG: u8 = 0x54;
    /// FIFO contents: `FIFO_WM_GT_TH` (5), `FIFO_HIRES_EN` (4),
    /// `FIFO_TMST_FSYNC_EN` (3), `FIFO_TEMP_EN` (2), `FIFO_GYRO_EN` (1),
    /// `FIFO_ACCEL_EN` (0).
    pub const FIFO_CONFIG1: u8 = 0x5F;
    /// FIFO watermark, bits 7:0.
    pub const FIFO_CONFIG2: u8 = 0x60;
    /// FIFO watermark, bits 11:8 (in bits 3:0).
    pub const FIFO_CONFIG3: u8 = 0x61;
    /// Identity register.
    pub const WHO_AM_I: u8 = 0x75;
    /// Register bank select.
    pub const REG_BANK_SEL: u8 = 0x76;
}

/// `WHO_AM_I` value of the ICM-42688-P.
pub const DEVICE_ID: u8 = 0x47;
/// Read flag in the SPI address byte.
const READ: u8 = 0x80;
/// Value the chip reports for a channel with no data.
pub const NO_DATA: i16 = i16::MIN;
/// Bytes of one burst: temperature, accelerometer, gyro.
const BURST: usize = 14;
/// `PWR_MGMT0`: gyro and accelerometer in low-noise mode.
const LOW_NOISE: u8 = 0b0000_1111;
const STANDARD_GRAVITY: f32 = 9.806_65;

/// Driver errors, generic over the bus error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI bus failed.
    Spi(E),
    /// `WHO_AM_I` returned something else (wiring, wrong chip, no chip).
    WrongDevice(u8),
    /// A channel read the chip's "no data" value (sensor off or not ready).
    NoData,
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Self::Spi(e)
    }
}

/// Gyro full scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GyroRange {
    /// ±2000 °/s (16.4 LSB per °/s).
    Dps2000 = 0,
    /// ±1000 °/s.
    Dps1000 = 1,
    /// ±500 °/s.
    Dps500 = 2,
    /// ±250 °/s.
    Dps250 = 3,
}

impl GyroRange {
    /// Full scale in °/s.
    pub fn full_scale_dps(self) -> f32 {
        match self {
            Self::Dps2000 => 2000.0,
            Self::Dps1000 => 1000.0,
            Self::Dps500 => 500.0,
            Self::Dps250 => 250.0,
        }
    }
}

/// Accelerometer full scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelRange {
    /// ±16 g (2048 LSB/g).
    G16 = 0,
    /// ±8 g.
    G8 = 1,
    /// ±4 g.
    G4 = 2,
    /// ±2 g.
    G2 = 3,
}

impl AccelRange {
    /// Full scale in g.
    pub fn full_scale_g(self) -> f32 {
        match self {
            Self::G16 => 16.0,
            Self::G8 => 8.0,
            Self::G4 => 4.0,
            Self::G2 => 2.0,
        }
    }
}

/// Output data rate (the chip's ODR codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Odr {
    /// 4 kHz (the FIFO holds 32 ms of packet 3).
    Hz4000 = 0b0100,
    /// 2 kHz (the FIFO holds 64 ms of packet 3).
    Hz2000 = 0b0101,
    /// 1 kHz.
    Hz1000 = 0b0110,
    /// 500 Hz.
    Hz500 = 0b1111,
    /// 200 Hz.
    Hz200 = 0b0111,
    /// 100 Hz.
    Hz100 = 0b1000,
    /// 50 Hz.
    Hz50 = 0b1001,
}

impl Odr {
    /// Sample period, µs (an integer for every rate offered).
    pub fn period_us(self) -> u32 {
        match self {
            Self::Hz4000 => 250,
            Self::Hz2000 => 500,
            Self::Hz1000 => 1_000,
            Self::Hz500 => 2_000,
            Self::Hz200 => 5_000,
            Self::Hz100 => 10_000,
            Self::Hz50 => 20_000,
        }
    }
}

/// Sensor configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Gyro full scale.
    pub gyro_range: GyroRange,
    /// Accelerometer full scale.
    pub accel_range: AccelRange,
    /// Output data rate of both sensors.
    pub odr: Odr,
    /// UI filter bandwidth code for both (0 = ODR/2 … 7 = ODR/40; see the
    /// datasheet's `GYRO_ACCEL_CONFIG0`).
    pub ui_filter_bw: u8,
}

impl Default for Config {
    /// ±2000 °/s, ±16 g, 1 kHz, bandwidth ODR/4 (code 1): a flight controller's setting.
    fn default() -> Self {
        Self {
            gyro_range: GyroRange::Dps2000,
            accel_range: AccelRange::G16,
            odr: Odr::Hz1000,
            ui_filter_bw: 1,
        }
    }
}

/// An ICM-42688-P on an SPI bus.
#[derive(Debug)]
pub struct Icm42688<SPI> {
    spi: SPI,
    config: Config,
    sequence: u32,
}

impl<SPI: SpiDevice> Icm42688<SPI> {
    /// Checks the identity, resets and configures the chip. `delay` waits
    /// out the reset (1 ms) and the gyro start-up (45 ms).
    pub fn new(
        spi: SPI,
        config: Config,
        delay: &mut impl DelayNs,
    ) -> Result<Self, Error<SPI::Error>> {
        let mut dev = Self {
            spi,
            config,
            sequence: 0,
        };
        let id = dev.read_register(reg::WHO_AM_I)?;
        if id != DEVICE_ID {
            return Err(Error::WrongDevice(id));
        }
        dev.write_register(reg::DEVICE_CONFIG, 0x01)?;
        delay.delay_ms(1);
        dev.write_register(reg::REG_BANK_SEL, 0)?;
        let id = dev.read_register(reg::WHO_AM_I)?;
        if id != DEVICE_ID {
            return Err(Error::WrongDevice(id));
        }
        let odr = config.odr as u8;
        dev.write_register(reg::GYRO_CONFIG0, ((config.gyro_range as u8) << 5) | odr)?;
        dev.write_register(reg::ACCEL_CONFIG0, ((config.accel_range as u8) << 5) | odr)?;
        let bw = config.ui_filter_bw & 0x0F;
        dev.write_register(reg::GYRO_ACCEL_CONFIG0, (bw << 4) | bw)?;
        dev.write_register(reg::PWR_MGMT0, LOW_NOISE)?;
        delay.delay_ms(45);
        Ok(dev)
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Reads one register.
    pub fn read_register(&mut self, addr: u8) -> Result<u8, Error<SPI::Error>> {
        let mut buf = [0u8; 1];
        self.spi
            .transaction(&mut [Operation::Write(&[addr | READ]), Operation::Read(&mut buf)])?;
        Ok(buf[0])
    }

    /// Writes one register.
    pub fn write_register(&mut self, addr: u8, value: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[addr & !READ, value])?;
        Ok(())
    }

    /// Accelerometer LSB at the configured full scale, m/s².
    pub fn accel_lsb(&self) -> f32 {
        self.config.accel_range.full_scale_g() * STANDARD_GRAVITY / 32768.0
    }

    /// Gyro LSB at the configured full scale, rad/s.
    pub fn gyro_lsb(&self) -> f32 {
        self.config.gyro_range.full_scale_dps().to_radians() / 32768.0
    }

    /// Reads `buf.len()` bytes starting at `addr` in one transaction
    /// (registers auto-increment; on `FIFO_DATA` every byte pops the FIFO).
    pub fn read_registers(&mut self, addr: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[addr | READ]), Operation::Read(buf)])?;
        Ok(())
    }

    /// Releases the bus.
    pub fn destroy(self) -> SPI {
        self.spi
    }

    /// Converts one 14-byte burst (temperature, accel xyz, gyro xyz, each
    /// big-endian i16) into SI units.
    pub fn convert(
        &self,
        raw: &[u8; BURST],
        sequence: u32,
    ) -> Result<ImuSample, Error<SPI::Error>> {
        let word = |i: usize| -> i16 {
            let hi = raw.get(2 * i).copied().unwrap_or(0);
            let lo = raw.get(2 * i + 1).copied().unwrap_or(0);
            i16::from_be_bytes([hi, lo])
        };
        let words: [i16; 7] = core::array::from_fn(word);
        if words.iter().skip(1).any(|w| *w == NO_DATA) {
            return Err(Error::NoData);
        }
        let accel_lsb = self.accel_lsb();
        let gyro_lsb = self.gyro_lsb();
        let [t, ax, ay, az, gx, gy, gz] = words;
        Ok(ImuSample {
            accel: [
                f32::from(ax) * accel_lsb,
                f32::from(ay) * accel_lsb,
                f32::from(az) * accel_lsb,
            ],
            gyro: [
                f32::from(gx) * gyro_lsb,
                f32::from(gy) * gyro_lsb,
                f32::from(gz) * gyro_lsb,
            ],
            // Datasheet: T(°C) = TEMP_DATA / 132.48 + 25.
            temperature: f32::from(t) / 132.48 + 25.0,
            sequence,
            timestamp_us: None,
        })
    }
}

impl<SPI: SpiDevice> Imu for Icm42688<SPI> {
    type Error = Error<SPI::Error>;

    fn read(&mut self) -> Result<ImuSample, Self::Error> {
        let mut raw = [0u8; BURST];
        self.spi.transaction(&mut [
            Operation::Write(&[reg::TEMP_DATA1 | READ]),
            Operation::Read(&mut raw),
        ])?;
        let s = self.convert(&raw, self.sequence)?;
        self.sequence = self.sequence.wrapping_add(1);
        Ok(s)
    }
}
