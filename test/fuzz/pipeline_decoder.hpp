// How a pipeline case's bytes become options and messages (every byte string decodes to some
// case; see byte_reader.hpp). The layout, which the binary seeds in test/data/fuzz/pipeline/
// follow:
//   3 header bytes: the rig and the options, each picked from a few values (decodeOptions)
//   then operations until the bytes run out (at most kMaxOperations), each an opcode byte:
//     0     torque:        stamp, value (no origin: any frame, unnumbered, not backlogged)
//     7     torque:        stamp, value, origin byte (frame, header.seq gaps or restarts,
//                          publisher, shed)
//     1     preload:       stamp, count (0..3), per setting: name, 4 values
//     2     observeClock:  stamp
//     3     damping ratios (RigPipeline::apply): 2 values
//     4     fidelity (apply): 1 byte
//     5     stiffness rate (apply): value
//     6     reset
//     0xE0-0xEF  vibration block (RigPipeline::vibration): stamp, layout byte (channel names,
//                header.seq numbering, a data size that is not a whole number of frames, a
//                poisoned sample), rate byte [, rate value], frames byte, amplitude value
//                [, poisoned sample index byte, value]; see decodeVibration
//     >= 0xF0  joint_states (RigPipeline::motion): stamp, flags byte (velocity, gear angle, a
//              missing pinion joint, header.seq numbering as opcode 7), pinion angle, [velocity],
//              [gear angle]
//   (opcode bytes below 0xE0 keep their meaning modulo 8, so older seeds still mean the same)
//   stamp: 1 mode byte, then 0 to 8 bytes: forward by up to 1 ms or 0.65 s, back by up to 0.65 s,
//          a burst (same stamp, or 1 ns steps), zero, or any (sec, nsec) pair a ROS header carries
//   value: 1 mode byte, then an "interesting" double (NaN, +-Inf, subnormals, limits and their
//          neighbours, ...), any 8-byte bit pattern, or a typical value scaled from 2 bytes
//
// The option values keep max_gap x output rate small, so that one accepted torque integrates at
// most ~1e4 output samples: every case costs bounded time by construction.
#pragma once

#include <vector>

#include "byte_reader.hpp"
#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness::fuzz {

constexpr int kMaxOperations = 64;

/// One joint_states message: the reading, or (missing) a message without the pinion joint.
struct MotionCase {
  MotionInput reading;
  bool missing_pinion = false;
  std::uint8_t numbering = 0;  ///< as opcode 7's origin byte, bits 3-7
};
MotionCase decodeMotion(ByteReader& in);

struct PipelineSetup {
  int rig = 0;  ///< 0: config/gearboxes/seed_servo.yaml (anti-backlash); 1:
                ///< test/data/ordinary_servo.yaml (backlash)
  PipelineOptions options;
  RuntimeSettings
      settings;  ///< the damping ratios: the rig's (RuntimeSettings::forRig), set by the caller
};

/// One VibrationBlock message: channel names, samples interleaved by frame, its header.seq rule.
struct VibrationCase {
  double sample_rate = 0.0;
  std::vector<std::string> channels;
  std::vector<float> data;
  std::uint8_t numbering = 0;  ///< 0 unnumbered, 1 the next number, 2 the same again, 3 one skipped
};
/// Rates from a table (the simulator's 51.2 kHz, within and past the rate tolerance, a 64 Hz rate
/// whose 4 s record a few blocks fill, zero, negative) or a value up to 51.2 kHz: no case
/// allocates a record much larger than the simulator's.
VibrationCase decodeVibration(ByteReader& in);

PipelineSetup decodeSetup(ByteReader& in);
Stamp decodeStamp(ByteReader& in, Stamp last);
/// `typical`: the scale of a typical value of this field.
double decodeValue(ByteReader& in, double typical);
std::vector<PreloadSetting> decodePreloads(ByteReader& in);
Fidelity decodeFidelity(std::uint8_t byte);

}  // namespace drivetrain_stiffness::fuzz
