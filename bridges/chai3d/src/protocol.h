// The UDP device protocol of Coiffure (docs/protocol.md): CFP1 poses to Coiffure, CFF1 forces back.
// All numbers little-endian; positions in m in the device frame (x right, y away from the user, z up).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

namespace coiffure {

constexpr std::size_t kPoseBytes = 116;
constexpr std::size_t kForceBytes = 64;
constexpr std::uint32_t kFlagRejected = 1;  // the pose answered was rejected; the force is zero
constexpr std::uint32_t kFlagWithheld = 2;  // the simulation's force was not finite; the force is zero

struct Pose {
    std::uint32_t seq = 0;
    double time = 0.0;                    // s
    std::array<double, 3> position{};     // m, device frame
    std::array<double, 9> rotation{};     // row-major, tool frame to device frame
    std::uint32_t buttons = 0;            // bit 0: primary
};

struct Force {
    std::uint32_t seq = 0;
    std::array<double, 3> force{};        // N on the hand, device frame
    std::array<double, 3> torque{};       // N m
    std::uint32_t flags = 0;
};

std::array<unsigned char, kPoseBytes> encode_pose(const Pose& p);
// False if `n` bytes at `b` are not a force packet (size or magic).
bool decode_force(const unsigned char* b, std::size_t n, Force& out);

}  // namespace coiffure
