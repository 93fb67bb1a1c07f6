//! IMU drivers: the [`Imu`] trait the monitor is fed through, and a real
//! driver for the TDK InvenSense ICM-42688-P over `embedded_hal::spi::SpiDevice`:
//! register reads ([`Icm42688`], the latest sample) or the FIFO at full
//! ODR integrated into the monitor period ([`Icm42688Fifo`], delta angle /
//! delta velocity with coning and sculling corrections: [`integrate`]).

pub mod fifo;
pub mod icm42688;
pub mod integrate;

pub use fifo::{FifoStatus, FifoTotals, Icm42688Fifo};
pub use icm42688::{AccelRange, Config, Error as Icm42688Error, GyroRange, Icm42688, Odr};
pub use integrate::{Delta, DeltaIntegrator};

/// One IMU sample in SI units, in the sensor's axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuSample {
    /// Specific force `[x, y, z]`, m/s².
    pub accel: [f32; 3],
    /// Angular rate `[x, y, z]`, rad/s.
    pub gyro: [f32; 3],
    /// Die temperature, °C.
    pub temperature: f32,
    /// Count of samples read since the driver started (wraps); a gap in the
    /// sequence seen by the caller means a missed period.
    pub sequence: u32,
    /// The sample's own time stamp, µs (wraps), when the driver has one
    /// (e.g. the chip's timestamp register or a data-ready capture). The
    /// monitor task then takes `dt` from the difference of two stamps read
    /// instead of the task's measured period.
    pub timestamp_us: Option<u32>,
}

impl ImuSample {
    /// The sample in the monitor's channel order `[a_x, a_y, a_z, p, q, r]`.
    pub fn channels(&self) -> [f32; 6] {
        let [ax, ay, az] = self.accel;
        let [p, q, r] = self.gyro;
        [ax, ay, az, p, q, r]
    }
}

/// A source of IMU samples.
pub trait Imu {
    /// Why a read failed.
    type Error;
    /// Reads the next sample: the latest one (register drivers: one bus
    /// transaction, never torn) or the average over the samples since the
    /// previous read (FIFO drivers, e.g. [`Icm42688Fifo`]).
    fn read(&mut self) -> Result<ImuSample, Self::Error>;
}
