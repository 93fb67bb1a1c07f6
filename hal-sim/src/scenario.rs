//! Scenarios as data: vehicle, sensors, aiding and a fault table.

use core::f64::consts::PI;

use imu_fdi::model::AidingKind;

use crate::fault::{FaultKind, FaultRow, FaultSizes};
use crate::imu_model::ImuErrors;
use crate::trajectory::Profile;

const DEG: f64 = PI / 180.0;

/// Most rows a scenario's fault table may have.
pub const MAX_FAULTS: usize = 32;

/// Aiding sensors: rates and noise.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct AidingSpec {
    /// M1 or M2.
    #[cfg_attr(feature = "std", serde(with = "aiding_kind_serde"))]
    pub kind: AidingKind,
    /// Velocity sensor rate, Hz (DVL or GNSS).
    pub vel_rate_hz: f64,
    /// Velocity noise σ, m/s.
    pub vel_sigma: f64,
    /// Attitude sensor rate, Hz (compass/AHRS or GNSS attitude).
    pub att_rate_hz: f64,
    /// Attitude noise σ `[roll, pitch, yaw]`, rad.
    pub att_sigma: [f64; 3],
    /// Latency of both aiding sensors, s: each value describes the vehicle
    /// this long before it is delivered.
    #[cfg_attr(feature = "std", serde(default))]
    pub delay_s: f64,
    /// Constant heading offset of the attitude aiding's frame from the
    /// IMU's, rad: the yaw it reports is the true yaw plus this (a
    /// mis-surveyed antenna baseline or AHRS mounting).
    #[cfg_attr(feature = "std", serde(default))]
    pub heading_offset_rad: f64,
}

#[cfg(feature = "std")]
mod aiding_kind_serde {
    use imu_fdi::model::AidingKind;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(k: &AidingKind, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(match k {
            AidingKind::DvlCompass => "dvl-compass",
            AidingKind::GnssAttitude => "gnss-attitude",
        })
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<AidingKind, D::Error> {
        let s = String::deserialize(d)?;
        match s.as_str() {
            "dvl-compass" => Ok(AidingKind::DvlCompass),
            "gnss-attitude" => Ok(AidingKind::GnssAttitude),
            other => Err(serde::de::Error::custom(format!(
                "unknown aiding kind '{other}'"
            ))),
        }
    }
}

impl AidingSpec {
    /// 5 Hz DVL (σ 0.01 m/s) and 10 Hz AHRS/compass (σ 0.02° roll/pitch,
    /// 0.05° heading).
    pub fn auv() -> Self {
        Self {
            kind: AidingKind::DvlCompass,
            vel_rate_hz: 5.0,
            vel_sigma: 0.01,
            att_rate_hz: 10.0,
            att_sigma: [0.02 * DEG, 0.02 * DEG, 0.05 * DEG],
            delay_s: 0.0,
            heading_offset_rad: 0.0,
        }
    }
    /// 10 Hz GNSS velocity (σ 0.05 m/s) and 10 Hz GNSS attitude (σ 0.1°
    /// roll/pitch, 0.2° heading; ≥ 3 antennas).
    pub fn aircraft() -> Self {
        Self {
            kind: AidingKind::GnssAttitude,
            vel_rate_hz: 10.0,
            vel_sigma: 0.05,
            att_rate_hz: 10.0,
            att_sigma: [0.1 * DEG, 0.1 * DEG, 0.2 * DEG],
            delay_s: 0.0,
            heading_offset_rad: 0.0,
        }
    }
}

/// A complete, reproducible simulation setup.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct Scenario {
    /// Short name (`s1`, `s2`, …).
    pub name: heapless::String<32>,
    /// Vehicle.
    pub profile: Profile,
    /// Length, s.
    pub duration_s: f64,
    /// IMU rate, Hz.
    pub imu_rate_hz: f64,
    /// IMU error model (SPEC §8a: never ideal in tests).
    pub imu_errors: ImuErrors,
    /// Aiding sensors.
    pub aiding: AidingSpec,
    /// Sizes of the fault shapes.
    pub sizes: FaultSizes,
    /// Smallest fault per channel that counts for the detection rate (SPEC §9).
    pub min_fault: [f64; 6],
    /// The fault table.
    pub faults: heapless::Vec<FaultRow, MAX_FAULTS>,
}

/// Fault sizes of the built-in S1/S2: accelerometer a = 0.3 m/s²,
/// b = 0.1 m/s³, c = 3 m/s²; gyro a = 1.5 °/s, b = 0.5 °/s², c = 15 °/s.
/// The smallest (0.3 m/s², 1.5 °/s steps) are ≥ 5× the residual bias the
/// learning phase leaves (measured: see the README).
pub const UKF_SIZES: FaultSizes = FaultSizes {
    accel: [0.3, 0.1, 3.0],
    gyro: [1.5 * DEG, 0.5 * DEG, 15.0 * DEG],
    f_unit: [1.0, DEG],
};

/// Minimum fault counted for the detection rate: 0.1 m/s², 0.5 °/s.
pub const UKF_MIN_FAULT: [f64; 6] = [0.1, 0.1, 0.1, 0.5 * DEG, 0.5 * DEG, 0.5 * DEG];

const fn row(channel: usize, start: f64, end: f64, kind: FaultKind, sign: f64) -> FaultRow {
    FaultRow {
        channel,
        start,
        end,
        kind,
        sign,
    }
}

/// \[UKF\] Table 1 (threshold method):
/// `a_x 11–16 E2; a_y 17–23 E1; a_z 24–29 E1; p 41–47 E3; q 48–52 −E1; r 53–59 E1`.
pub const S1_TABLE: [FaultRow; 6] = [
    row(0, 11.0, 16.0, FaultKind::E2, 1.0),
    row(1, 17.0, 23.0, FaultKind::E1, 1.0),
    row(2, 24.0, 29.0, FaultKind::E1, 1.0),
    row(3, 41.0, 47.0, FaultKind::E3, 1.0),
    row(4, 48.0, 52.0, FaultKind::E1, -1.0),
    row(5, 53.0, 59.0, FaultKind::E1, 1.0),
];

/// \[UKF\] Table 2 (decoupling method):
/// `a_x 11–20 E2; a_y 11–20 E1; a_z 11–20 E3; p 35–39 E2; q 50–58 E3; r 43–48 E1`.
pub const S2_TABLE: [FaultRow; 6] = [
    row(0, 11.0, 20.0, FaultKind::E2, 1.0),
    row(1, 11.0, 20.0, FaultKind::E1, 1.0),
    row(2, 11.0, 20.0, FaultKind::E3, 1.0),
    row(3, 35.0, 39.0, FaultKind::E2, 1.0),
    row(4, 50.0, 58.0, FaultKind::E3, 1.0),
    row(5, 43.0, 48.0, FaultKind::E1, 1.0),
];

/// \[OTS\] Table 1 (S3), windows 10–20 / 25–35 / 40–50 s:
///
/// ```text
///         10–20 s  25–35 s  40–50 s
/// f_ax      F1      −F2      F3
/// f_ay      F2      −F3      F1
/// f_az      F3      −F1      F2
/// f_p       F1      −F2      F3
/// f_q       F2      −F3      F1
/// f_r       F3      −F1      F2
/// ```
pub const S3_TABLE: [FaultRow; 18] = {
    use FaultKind::{F1, F2, F3};
    const SHAPES: [[FaultKind; 3]; 3] = [[F1, F2, F3], [F2, F3, F1], [F3, F1, F2]];
    let mut rows = [row(0, 0.0, 0.0, F1, 1.0); 18];
    let windows = [(10.0, 20.0, 1.0), (25.0, 35.0, -1.0), (40.0, 50.0, 1.0)];
    let mut ch = 0;
    while ch < 6 {
        let mut w = 0;
        while w < 3 {
            let (start, end, sign) = windows[w];
            rows[ch * 3 + w] = row(ch, start, end, SHAPES[ch % 3][w], sign);
            w += 1;
        }
        ch += 1;
    }
    rows
};

/// S3 units: F1–F3 in m/s² for the accelerometers and in °/s for the gyros
/// (the paper does not state its gyro unit; 1 °/s is the reading that its
/// RMSE of 0.085 makes plausible).
pub const OTS_SIZES: FaultSizes = FaultSizes {
    accel: UKF_SIZES.accel,
    gyro: UKF_SIZES.gyro,
    f_unit: [1.0, DEG],
};

fn name(s: &str) -> heapless::String<32> {
    let mut n = heapless::String::new();
    for c in s.chars().take(32) {
        // Cannot overflow: at most 32 characters are taken.
        let _ = n.push(c);
    }
    n
}

/// S5: the SPEC §8 hardware faults, one per channel, on the AUV
/// (stuck, dropout of the whole sample, clipping, spike bursts, noise ×10,
/// scale factor +5 %).
pub const S5_TABLE: [FaultRow; 6] = [
    row(5, 10.0, 15.0, FaultKind::Stuck, 1.0),
    row(0, 20.0, 21.0, FaultKind::Dropout, 1.0),
    row(0, 30.0, 35.0, FaultKind::Clip(0.2), 1.0),
    row(4, 40.0, 45.0, FaultKind::Spikes(0.5), 1.0),
    row(2, 50.0, 55.0, FaultKind::NoiseIncrease(10.0), 1.0),
    row(3, 60.0, 65.0, FaultKind::ScaleFactor(0.05), 1.0),
];

fn table(rows: &[FaultRow]) -> heapless::Vec<FaultRow, MAX_FAULTS> {
    rows.iter().take(MAX_FAULTS).copied().collect()
}

impl Scenario {
    /// An AUV run of `duration_s` with the M1 aiding and no fault.
    pub fn auv_fault_free(duration_s: f64) -> Self {
        Self {
            name: name("auv-fault-free"),
            profile: Profile::Auv,
            duration_s,
            imu_rate_hz: 100.0,
            imu_errors: ImuErrors::mems_auv(),
            aiding: AidingSpec::auv(),
            sizes: UKF_SIZES,
            min_fault: UKF_MIN_FAULT,
            faults: heapless::Vec::new(),
        }
    }

    /// An aircraft run of `duration_s` with the M2 aiding and no fault.
    pub fn aircraft_fault_free(duration_s: f64) -> Self {
        Self {
            name: name("aircraft-fault-free"),
            profile: Profile::Aircraft,
            imu_errors: ImuErrors::mems_aircraft(),
            aiding: AidingSpec::aircraft(),
            min_fault: [0.3, 0.3, 0.3, 1.5 * DEG, 1.5 * DEG, 1.5 * DEG],
            ..Self::auv_fault_free(duration_s)
        }
    }

    /// S1: \[UKF\] Table 1 on the AUV, 65 s.
    pub fn s1() -> Self {
        Self {
            name: name("s1"),
            faults: table(&S1_TABLE),
            ..Self::auv_fault_free(65.0)
        }
    }

    /// S2: \[UKF\] Table 2 on the AUV, 65 s.
    pub fn s2() -> Self {
        Self {
            name: name("s2"),
            faults: table(&S2_TABLE),
            ..Self::auv_fault_free(65.0)
        }
    }

    /// S5: the hardware faults of [`S5_TABLE`] on the AUV, 70 s.
    pub fn s5() -> Self {
        Self {
            name: name("s5"),
            faults: table(&S5_TABLE),
            ..Self::auv_fault_free(70.0)
        }
    }

    /// S3: \[OTS\] Table 1 on the aircraft in gusty wind, 60 s, realistic
    /// sensors: MEMS errors of SPEC §8a, GNSS velocity (σ 0.05 m/s) and
    /// attitude (σ 0.1° roll/pitch, 0.2° heading) at 10 Hz.
    pub fn s3() -> Self {
        Self {
            name: name("s3"),
            profile: Profile::AircraftWind,
            sizes: OTS_SIZES,
            faults: table(&S3_TABLE),
            ..Self::aircraft_fault_free(60.0)
        }
    }

    /// S3 in the paper's setting (\[OTS\] eq. (27)): ideal IMU with white
    /// noise of variance 1e-4 (m/s²)² and 3e-8 (rad/s)² per 100 Hz sample,
    /// GNSS velocity and attitude at the IMU rate with the same variances
    /// (σ 0.01 m/s, 0.0099°).
    pub fn s3_paper() -> Self {
        let mut imu_errors = ImuErrors::mems_aircraft().ideal_with_noise();
        // Per-sample σ at 100 Hz → density σ/√rate.
        imu_errors.accel.noise_density = 1e-2 / 10.0;
        imu_errors.gyro.noise_density = libm::sqrt(3e-8) / 10.0;
        let att = libm::sqrt(3e-8);
        Self {
            name: name("s3-paper"),
            imu_errors,
            aiding: AidingSpec {
                kind: AidingKind::GnssAttitude,
                vel_rate_hz: 100.0,
                vel_sigma: 1e-2,
                att_rate_hz: 100.0,
                att_sigma: [att, att, att],
                delay_s: 0.0,
                heading_offset_rad: 0.0,
            },
            ..Self::s3()
        }
    }

    /// A built-in scenario by name.
    pub fn builtin(name: &str) -> Option<Self> {
        match name {
            "s1" | "S1" => Some(Self::s1()),
            "s2" | "S2" => Some(Self::s2()),
            "auv-hour" => Some(Self::auv_fault_free(3600.0)),
            "aircraft-hour" => Some(Self::aircraft_fault_free(3600.0)),
            "s3" | "S3" => Some(Self::s3()),
            "s3-paper" => Some(Self::s3_paper()),
            "s5" | "S5" => Some(Self::s5()),
            _ => None,
        }
    }

    /// Names accepted by [`Scenario::builtin`].
    pub const BUILTIN: [&'static str; 7] = [
        "s1",
        "s2",
        "s3",
        "s3-paper",
        "s5",
        "auv-hour",
        "aircraft-hour",
    ];

    /// The additive fault on every channel at `t`.
    pub fn fault_at(&self, t: f64) -> [f64; 6] {
        let mut f = [0.0; 6];
        for r in self.faults.iter() {
            if let Some(v) = f.get_mut(r.channel) {
                *v += r.additive(t, &self.sizes);
            }
        }
        f
    }

    /// Whether any fault row is active on `channel` at `t`.
    pub fn fault_active(&self, channel: usize, t: f64) -> bool {
        self.faults
            .iter()
            .any(|r| r.channel == channel && r.active(t))
    }
}
