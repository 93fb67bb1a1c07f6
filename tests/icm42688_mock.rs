//! ICM-42688-P driver against mocked SPI transactions: the exact register
//! sequence, scaling, the "no data" value and bus errors.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::needless_range_loop
)] // test code: a panic is a failed assertion

use embedded_hal::spi::ErrorKind;
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock, Transaction as T};
use imu_fdi::imu::icm42688::{reg, Config, Error, Icm42688, DEVICE_ID};
use imu_fdi::imu::Imu;

fn read_reg(addr: u8, value: u8) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write(addr | 0x80),
        T::read(value),
        T::transaction_end(),
    ]
}

fn write_reg(addr: u8, value: u8) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write_vec(vec![addr, value]),
        T::transaction_end(),
    ]
}

fn init_sequence() -> Vec<T<u8>> {
    let mut t = read_reg(reg::WHO_AM_I, DEVICE_ID);
    t.extend(write_reg(reg::DEVICE_CONFIG, 0x01));
    t.extend(write_reg(reg::REG_BANK_SEL, 0));
    t.extend(read_reg(reg::WHO_AM_I, DEVICE_ID));
    // ±2000 °/s, ±16 g, 1 kHz (0b0110), bandwidth code 1 for both.
    t.extend(write_reg(reg::GYRO_CONFIG0, 0b0000_0110));
    t.extend(write_reg(reg::ACCEL_CONFIG0, 0b0000_0110));
    t.extend(write_reg(reg::GYRO_ACCEL_CONFIG0, 0x11));
    t.extend(write_reg(reg::PWR_MGMT0, 0x0F));
    t
}

fn burst(words: [i16; 7]) -> Vec<T<u8>> {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
    vec![
        T::transaction_start(),
        T::write(reg::TEMP_DATA1 | 0x80),
        T::read_vec(bytes),
        T::transaction_end(),
    ]
}

#[test]
fn initialises_with_the_documented_register_sequence() {
    let mut spi = Mock::new(&init_sequence());
    let dev = Icm42688::new(spi.clone(), Config::default(), &mut NoopDelay::new()).unwrap();
    drop(dev.destroy());
    spi.done();
}

#[test]
fn wrong_identity_is_reported() {
    let mut spi = Mock::new(&read_reg(reg::WHO_AM_I, 0x12));
    let r = Icm42688::new(spi.clone(), Config::default(), &mut NoopDelay::new());
    assert_eq!(r.err(), Some(Error::WrongDevice(0x12)));
    spi.done();
}

#[test]
fn one_burst_is_scaled_big_endian_with_sign() {
    let mut t = init_sequence();
    // temp 0 → 25 °C; accel z = −2048 LSB = −1 g at ±16 g; gyro x = +3277 LSB ≈ 200 °/s, gyro z = −32767.
    t.extend(burst([0, 0, 1, -2048, 3277, 0, -32767]));
    t.extend(burst([1325, 0, 0, 2048, 0, 0, 0]));
    let mut spi = Mock::new(&t);
    let mut dev = Icm42688::new(spi.clone(), Config::default(), &mut NoopDelay::new()).unwrap();
    let s = dev.read().unwrap();
    assert_eq!(s.sequence, 0);
    assert!((s.temperature - 25.0).abs() < 1e-6);
    assert!((s.accel[2] + 9.80665).abs() < 1e-5, "{}", s.accel[2]);
    assert!((s.accel[1] - 9.80665 * 16.0 / 32768.0).abs() < 1e-7);
    assert!((s.gyro[0].to_degrees() - 3277.0 * 2000.0 / 32768.0).abs() < 1e-3);
    assert!((s.gyro[2].to_degrees() + 32767.0 * 2000.0 / 32768.0).abs() < 1e-2);
    let s = dev.read().unwrap();
    assert_eq!(s.sequence, 1);
    assert!((s.temperature - (1325.0 / 132.48 + 25.0)).abs() < 1e-4);
    drop(dev.destroy());
    spi.done();
}

#[test]
fn no_data_value_is_an_error() {
    let mut t = init_sequence();
    t.extend(burst([0, 0, 0, 0, i16::MIN, 0, 0]));
    let mut spi = Mock::new(&t);
    let mut dev = Icm42688::new(spi.clone(), Config::default(), &mut NoopDelay::new()).unwrap();
    assert_eq!(dev.read(), Err(Error::NoData));
    drop(dev.destroy());
    spi.done();
}

/// embedded-hal-mock 0.11 cannot inject SPI errors: this wrapper fails the
/// `fail_at`-th transaction (0-based) without touching the bus.
struct Flaky<S> {
    inner: S,
    calls: usize,
    fail_at: usize,
}

impl<S> embedded_hal::spi::ErrorType for Flaky<S> {
    type Error = ErrorKind;
}

impl<S: embedded_hal::spi::SpiDevice<u8, Error = ErrorKind>> embedded_hal::spi::SpiDevice<u8>
    for Flaky<S>
{
    fn transaction(
        &mut self,
        ops: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), ErrorKind> {
        let n = self.calls;
        self.calls += 1;
        if n == self.fail_at {
            return Err(ErrorKind::ChipSelectFault);
        }
        self.inner.transaction(ops)
    }
}

#[test]
fn bus_errors_are_typed_and_recoverable() {
    let mut t = init_sequence();
    let init_calls = 8;
    t.extend(burst([0, 0, 0, -2048, 0, 0, 0]));
    let mut spi = Mock::new(&t);
    let flaky = Flaky {
        inner: spi.clone(),
        calls: 0,
        fail_at: init_calls,
    };
    let mut dev = Icm42688::new(flaky, Config::default(), &mut NoopDelay::new()).unwrap();
    assert_eq!(dev.read(), Err(Error::Spi(ErrorKind::ChipSelectFault)));
    // The next period reads normally.
    assert!(dev.read().is_ok());
    drop(dev.destroy());
    spi.done();
}

/// The FIFO path, byte for byte: configuration (DS-000347 register values)
/// and one read of two packet-3 records.
#[test]
fn fifo_configuration_and_read_are_the_documented_bytes() {
    use imu_fdi::imu::fifo::Icm42688Fifo;
    let mut t = init_sequence();
    t.extend(write_reg(reg::INTF_CONFIG0, 0x73)); // records, big endian, SPI
    t.extend(read_reg(reg::TMST_CONFIG, 0x23)); // reset value
    t.extend(write_reg(reg::TMST_CONFIG, 0x2B)); // + TMST_RES 16 µs, no delta
    t.extend(write_reg(reg::FIFO_CONFIG1, 0x2F)); // packet 3, WM ≥ threshold
    t.extend(write_reg(reg::FIFO_CONFIG2, 20));
    t.extend(write_reg(reg::FIFO_CONFIG3, 0));
    t.extend(write_reg(reg::FIFO_CONFIG, 0xC0)); // stop-on-full
    t.extend(write_reg(reg::SIGNAL_PATH_RESET, 0x02)); // flush
                                                       // INT_STATUS (FIFO_THS), FIFO_COUNT = 2 records.
    t.extend(vec![
        T::transaction_start(),
        T::write(reg::INT_STATUS | 0x80),
        T::read_vec(vec![0x04, 0x00, 0x02]),
        T::transaction_end(),
    ]);
    let packet = |ax: i16, gz: i16, temp: i8, ts: u16| -> Vec<u8> {
        let mut p = vec![0x68];
        for w in [ax, 0, -2048, 0, 0, gz] {
            p.extend(w.to_be_bytes());
        }
        p.push(temp as u8);
        p.extend(ts.to_be_bytes());
        p
    };
    let mut data = packet(100, 1640, 10, 1000);
    data.extend(packet(300, 1640, 10, 1062)); // 62 × 16 µs later: the next sample
    t.extend(vec![
        T::transaction_start(),
        T::write(reg::FIFO_DATA | 0x80),
        T::read_vec(data),
        T::transaction_end(),
    ]);
    let mut spi = Mock::new(&t);
    let dev = Icm42688::new(spi.clone(), Config::default(), &mut NoopDelay::new()).unwrap();
    let mut fifo: Icm42688Fifo<_> = Icm42688Fifo::new(dev, 20).unwrap();
    let s = fifo.read().unwrap();
    let st = *fifo.fifo_status();
    assert_eq!((st.count, st.samples, st.packets_lost), (2, 2, 0));
    assert!(st.watermark_reached && !st.overflowed);
    // The mean of the two samples: ax (100 + 300)/2 LSB at ±16 g.
    let alsb = 16.0 * 9.80665 / 32768.0;
    assert!((s.accel[0] - 200.0 * alsb).abs() < 1e-5, "{}", s.accel[0]);
    assert!((s.accel[2] + 9.80665).abs() < 1e-4);
    // 1640 LSB at ±2000 °/s = 100.1 °/s.
    assert!((s.gyro[2].to_degrees() - 1640.0 * 2000.0 / 32768.0).abs() < 1e-3);
    assert!((s.temperature - (10.0 / 2.07 + 25.0)).abs() < 1e-4);
    assert_eq!(s.timestamp_us, Some(2_000));
    drop(fifo.destroy().destroy());
    spi.done();
}

/// A chip that answers whatever the test scripted: status, count and FIFO
/// bytes of any content, and optionally a failing transaction.
struct ScriptedFifo {
    status: [u8; 3],
    data: Vec<u8>,
    pos: usize,
    fail_transaction: Option<usize>,
    transactions: usize,
}

impl embedded_hal::spi::ErrorType for ScriptedFifo {
    type Error = ErrorKind;
}

impl embedded_hal::spi::SpiDevice<u8> for ScriptedFifo {
    fn transaction(
        &mut self,
        ops: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), ErrorKind> {
        use embedded_hal::spi::Operation;
        let n = self.transactions;
        self.transactions += 1;
        if self.fail_transaction == Some(n) {
            return Err(ErrorKind::Other);
        }
        let mut addr = None;
        for op in ops.iter_mut() {
            match op {
                Operation::Write(b) => addr = b.first().copied(),
                Operation::Read(buf) => match addr {
                    Some(a) if a == (reg::INT_STATUS | 0x80) => {
                        for (x, s) in buf.iter_mut().zip(self.status) {
                            *x = s;
                        }
                        // INT_STATUS clears on read.
                        self.status[0] = 0;
                    }
                    Some(a) if a == (reg::FIFO_DATA | 0x80) => {
                        for x in buf.iter_mut() {
                            *x = self.data.get(self.pos).copied().unwrap_or(0xFF);
                            self.pos += 1;
                        }
                    }
                    // WHO_AM_I and any other register.
                    _ => buf.fill(DEVICE_ID),
                },
                _ => {}
            }
        }
        Ok(())
    }
}

fn scripted(status: [u8; 3], data: Vec<u8>) -> ScriptedFifo {
    ScriptedFifo {
        status,
        data,
        pos: 0,
        fail_transaction: None,
        transactions: 0,
    }
}

proptest::proptest! {
    /// Any status, count and FIFO content: the FIFO driver returns a
    /// sample with finite values or a typed error, never panics.
    #[test]
    fn fifo_driver_never_panics_on_any_bytes(
        status in proptest::array::uniform3(proptest::num::u8::ANY),
        data in proptest::collection::vec(proptest::num::u8::ANY, 0..2200),
        valid_headers in proptest::bool::ANY,
    ) {
        use imu_fdi::imu::fifo::Icm42688Fifo;
        let mut data = data;
        if valid_headers {
            // Mostly well-formed packets with random contents.
            for p in data.chunks_mut(16) {
                p[0] = 0x68;
            }
        }
        let spi = scripted(status, data);
        let dev = Icm42688::new(spi, Config::default(), &mut NoopDelay::new()).unwrap();
        let mut fifo: Icm42688Fifo<_, 8> = Icm42688Fifo::new(dev, 20).unwrap();
        for _ in 0..3 {
            match fifo.read() {
                Ok(s) => {
                    proptest::prop_assert!(s.accel.iter().chain(s.gyro.iter()).all(|x| x.is_finite()));
                    proptest::prop_assert!(s.temperature.is_finite());
                }
                Err(e) => proptest::prop_assert!(matches!(e, Error::NoData)),
            }
        }
    }
}

/// A bus error on the data burst after `INT_STATUS` was read (and so
/// cleared on the chip): the overflow is reported by the next read, not lost.
#[test]
fn overflow_flag_survives_a_failed_data_burst() {
    use imu_fdi::imu::fifo::Icm42688Fifo;
    let mut packet = vec![0x68];
    for w in [0i16, 0, -2048, 0, 0, 0] {
        packet.extend(w.to_be_bytes());
    }
    packet.extend([0, 0, 10]);
    let mut spi = scripted([0x02, 0, 1], packet.clone());
    // 8 transactions of initialisation, 8 of FIFO set-up (one is a read),
    // then the first read's status burst (16) and data burst (17).
    spi.fail_transaction = Some(17);
    let dev = Icm42688::new(spi, Config::default(), &mut NoopDelay::new()).unwrap();
    let mut fifo: Icm42688Fifo<_> = Icm42688Fifo::new(dev, 20).unwrap();
    assert_eq!(fifo.read(), Err(Error::Spi(ErrorKind::Other)));
    // The chip has cleared FIFO_FULL_INT by now; the driver has not forgotten.
    let s = fifo.read().unwrap();
    assert!(fifo.fifo_status().overflowed);
    assert_eq!(fifo.fifo_totals().overflows, 1);
    assert!((s.accel[2] + 9.80665).abs() < 1e-4);
    // And reports it once.
    assert_eq!(fifo.read(), Err(Error::NoData));
    assert!(!fifo.fifo_status().overflowed);
}
