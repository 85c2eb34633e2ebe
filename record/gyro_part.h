#pragma once
// The gyro parts the recorder reads, their register maps (the facts the driver and the emulator
// share, so that they cannot disagree) and how a requested rate and range become register values.
//
// Sources: InvenSense MPU-9250 Register Map and Descriptions rev 1.6 and Product Specification rev
// 1.1 (the MPU-6500 has the same map and answers WHO_AM_I 0x70); TDK InvenSense ICM-42688-P
// datasheet DS-000347 rev 1.2 (bank 0 registers, FIFO packet 1).

#include <cstdint>
#include <string>

namespace shutterlab {

enum class GyroPart { kMpu9250, kMpu6500, kIcm42688p };

// MPU-9250 / MPU-6500 register addresses and bits.
namespace mpu {
inline constexpr uint8_t kSmplrtDiv = 0x19;  // sample rate = 1 kHz / (1 + div) when the DLPF is on
inline constexpr uint8_t kConfig =
    0x1A;  // bit 6 FIFO_MODE (1: drop new data when full), 2:0 DLPF_CFG
inline constexpr uint8_t kGyroConfig = 0x1B;   // 4:3 GYRO_FS_SEL, 1:0 FCHOICE_B
inline constexpr uint8_t kAccelConfig = 0x1C;  // 4:3 ACCEL_FS_SEL: +-2, 4, 8, 16 g
inline constexpr uint8_t kFifoEn = 0x23;       // 7 TEMP, 6 GYRO_X, 5 GYRO_Y, 4 GYRO_Z, 3 ACCEL
inline constexpr uint8_t kIntEnable = 0x38;    // bit 4 FIFO_OFLOW_EN
inline constexpr uint8_t kIntStatus = 0x3A;    // bit 4 FIFO_OFLOW_INT; cleared by reading it
inline constexpr uint8_t kAccelXoutH = 0x3B;   // 0x3B..0x40 accel, 0x41..0x42 temp, 0x43..0x48 gyro
inline constexpr uint8_t kGyroXoutH = 0x43;
inline constexpr uint8_t kUserCtrl = 0x6A;    // 6 FIFO_EN, 4 I2C_IF_DIS, 2 FIFO_RST (self-clearing)
inline constexpr uint8_t kPwrMgmt1 = 0x6B;    // 7 H_RESET, 6 SLEEP, 2:0 CLKSEL
inline constexpr uint8_t kPwrMgmt2 = 0x6C;    // 2:0 DIS_XG, DIS_YG, DIS_ZG
inline constexpr uint8_t kFifoCountH = 0x72;  // 4:0 count[12:8]; 0x73 count[7:0] (bytes)
inline constexpr uint8_t kFifoRw = 0x74;      // FIFO data: reads stream the FIFO
inline constexpr uint8_t kWhoAmI = 0x75;
inline constexpr uint8_t kFifoOverflowBit = 0x10;
inline constexpr uint8_t kFifoGyroXyz = 0x70;
inline constexpr uint8_t kUserCtrlFifoEn = 0x40, kUserCtrlI2cIfDis = 0x10, kUserCtrlFifoRst = 0x04;
inline constexpr uint8_t kConfigFifoModeStop = 0x40;
inline constexpr uint8_t kPwrMgmt1Reset = 0x80, kPwrMgmt1Sleep = 0x40;
}  // namespace mpu

// ICM-42688-P bank 0 register addresses and bits.
namespace icm {
inline constexpr uint8_t kDeviceConfig = 0x11;  // bit 0 SOFT_RESET_CONFIG
inline constexpr uint8_t kFifoConfig = 0x16;  // 7:6 FIFO_MODE: 0 bypass, 1 stream, 2/3 stop on full
inline constexpr uint8_t kAccelDataX1 = 0x1F;      // 0x1F..0x24 accel, big-endian by default
inline constexpr uint8_t kGyroDataX1 = 0x25;       // 0x25..0x2A gyro, big-endian by default
inline constexpr uint8_t kIntStatus = 0x2D;        // bit 1 FIFO_FULL_INT; cleared by reading it
inline constexpr uint8_t kFifoCountH = 0x2E;       // 0x2E, 0x2F: FIFO count (bytes, big-endian)
inline constexpr uint8_t kFifoData = 0x30;         // reads stream the FIFO
inline constexpr uint8_t kSignalPathReset = 0x4B;  // bit 1 FIFO_FLUSH
inline constexpr uint8_t kIntfConfig0 = 0x4C;   // 6 FIFO_COUNT_REC, 5 COUNT_ENDIAN, 4 DATA_ENDIAN
inline constexpr uint8_t kPwrMgmt0 = 0x4E;      // 3:2 GYRO_MODE (3 = low noise)
inline constexpr uint8_t kGyroConfig0 = 0x4F;   // 7:5 GYRO_FS_SEL, 3:0 GYRO_ODR
inline constexpr uint8_t kAccelConfig0 = 0x50;  // 7:5 ACCEL_FS_SEL: +-16, 8, 4, 2 g
inline constexpr uint8_t kFifoConfig1 = 0x5F;   // 2 TEMP_EN, 1 GYRO_EN, 0 ACCEL_EN
inline constexpr uint8_t kWhoAmI = 0x75;
inline constexpr uint8_t kBankSel = 0x76;
inline constexpr uint8_t kFifoFullBit = 0x02;
inline constexpr uint8_t kFifoFlushBit = 0x02;
inline constexpr uint8_t kFifoModeStopOnFull = 0x80;
inline constexpr uint8_t kGyroModeLowNoise = 0x0C;
inline constexpr uint8_t kFifoGyroTemp = 0x06;  // packet 1: header, gyro x/y/z, temperature
inline constexpr uint8_t kHeaderEmpty = 0x80, kHeaderAccel = 0x40, kHeaderGyro = 0x20;
inline constexpr uint8_t kIntfConfig0Default = 0x30;  // counts and data big-endian
}  // namespace icm

// What is fixed by the part.
struct PartInfo {
  GyroPart part;
  const char* name;         // "MPU-9250"
  const char* key;          // "mpu9250": the name on the command line
  uint8_t who_am_i;         // the WHO_AM_I answer
  uint8_t who_am_i_reg;     // its address
  int fifo_bytes;           // FIFO size
  int packet_bytes;         // one gyro sample in the FIFO as the driver configures it
  int64_t gyro_startup_ns;  // gyro start-up time from sleep (datasheet, typical)
  uint32_t spi_config_hz;   // SPI clock for register writes
  uint32_t spi_data_hz;     // SPI clock for sensor and FIFO reads
  double max_rate_hz;       // the highest FIFO rate the recorder uses
};

const PartInfo& GetPartInfo(GyroPart part);
// "mpu9250", "mpu6500", "icm42688p" (also "icm42688"); throws std::invalid_argument otherwise.
GyroPart ParseGyroPart(const std::string& text);

// What the user asks for.
struct SensorConfig {
  double rate_hz = 8000.0;  // wanted output data rate; the part's nearest rate at or above it
  int range_dps = 250;      // full scale: 250, 500, 1000 or 2000 deg/s
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// What the part will do, and the register fields that give it.
struct PartSetting {
  GyroPart part = GyroPart::kMpu9250;
  double odr_hz = 0.0;  // nominal output data rate (the part's own clock)
  int range_dps = 250;
  double lsb_per_dps = 131.0;   // counts per deg/s
  double bandwidth_hz = 0.0;    // the gyro's low-pass bandwidth at this setting (3 dB)
  double filter_delay_s = 0.0;  // its delay (GyroFilter::delay_s), taken off every sample's time
  // MPU-9250 / MPU-6500: SMPLRT_DIV, DLPF_CFG, FCHOICE_B and GYRO_FS_SEL.
  uint8_t smplrt_div = 0, dlpf_cfg = 0, fchoice_b = 0, fs_sel = 0;
  // ICM-42688-P: GYRO_ODR and GYRO_FS_SEL codes of GYRO_CONFIG0.
  uint8_t icm_odr_code = 0, icm_fs_code = 0;
  std::string Describe() const;  // "8000 Hz (SMPLRT_DIV 0; DLPF_CFG 0: 250 Hz bandwidth); +-250
                                 // deg/s (131 LSB per deg/s)"
};

// The setting a part gives for a request: the lowest rate the part offers at or above rate_hz
// (its highest when none is), the range as asked. Throws std::invalid_argument for a rate above
// the part's highest or a range it lacks.
PartSetting ResolvePartSetting(GyroPart part, const SensorConfig& config);

// "0x71": a register value as the datasheets write it.
std::string HexByte(uint8_t value);

// The MPU's rate and bandwidth from its registers, as the part computes them: FCHOICE_B != 0:
// 32 kHz; DLPF_CFG 0 or 7: 8 kHz; otherwise 1 kHz / (1 + SMPLRT_DIV).
double MpuRateHz(uint8_t smplrt_div, uint8_t dlpf_cfg, uint8_t fchoice_b);
// The gyro's digital low-pass filter at a register setting.
struct GyroFilter {
  double bandwidth_hz;      // 3 dB
  double delay_s;           // the delay of a slow motion through it (group delay at low frequency)
  double internal_rate_hz;  // the rate it runs at, before SMPLRT_DIV keeps one sample in 1 + div
  bool from_datasheet;      // false: modelled (a first-order filter at the bandwidth)
};
// The MPU-9250 / MPU-6500 gyro filter (register map, CONFIG: DLPF_CFG with FCHOICE_B 00, and
// FCHOICE_B x1 and 10): bandwidth, delay and rate as the table gives them.
GyroFilter MpuGyroFilter(uint8_t dlpf_cfg, uint8_t fchoice_b);
// The ICM-42688-P's default UI filter (GYRO_UI_FILT_BW 1: max(400 Hz, ODR) / 4) at a rate. Its
// delay is modelled as a first-order filter's at that bandwidth: the datasheet's table of the
// filter's delays is not reproduced here.
GyroFilter IcmGyroFilter(double odr_hz);

// The ICM-42688-P's GYRO_ODR code in Hz; 0 for a reserved code.
double IcmRateHz(uint8_t odr_code);
// The accelerometer's counts per g at its ACCEL_FS_SEL code: MPU 16384 / 2^code (+-2 g at 0),
// ICM-42688-P 2048 * 2^code (+-16 g at 0).
double AccelLsbPerG(GyroPart part, uint8_t fs_code);
// The ICM-42688-P's GYRO_FS_SEL code in deg/s (2000 / 2^code).
double IcmRangeDps(uint8_t fs_code);

}  // namespace shutterlab
