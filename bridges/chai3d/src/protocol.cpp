#include "protocol.h"

#include <cstring>

namespace coiffure {
namespace {

bool little_endian() {
    const std::uint16_t one = 1;
    unsigned char b;
    std::memcpy(&b, &one, 1);
    return b == 1;
}

template <typename T>
void put(unsigned char* b, std::size_t at, T v) {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    if (!little_endian()) {
        for (std::size_t i = 0; i < sizeof(T); ++i) b[at + i] = raw[sizeof(T) - 1 - i];
    } else {
        std::memcpy(b + at, raw, sizeof(T));
    }
}

template <typename T>
T get(const unsigned char* b, std::size_t at) {
    unsigned char raw[sizeof(T)];
    if (!little_endian()) {
        for (std::size_t i = 0; i < sizeof(T); ++i) raw[i] = b[at + sizeof(T) - 1 - i];
    } else {
        std::memcpy(raw, b + at, sizeof(T));
    }
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
}

}  // namespace

std::array<unsigned char, kPoseBytes> encode_pose(const Pose& p) {
    std::array<unsigned char, kPoseBytes> b{};
    std::memcpy(b.data(), "CFP1", 4);
    put(b.data(), 4, p.seq);
    put(b.data(), 8, p.time);
    for (int k = 0; k < 3; ++k) put(b.data(), 16 + 8 * k, p.position[k]);
    for (int k = 0; k < 9; ++k) put(b.data(), 40 + 8 * k, p.rotation[k]);
    put(b.data(), 112, p.buttons);
    return b;
}

bool decode_force(const unsigned char* b, std::size_t n, Force& out) {
    if (n != kForceBytes || std::memcmp(b, "CFF1", 4) != 0) return false;
    out.seq = get<std::uint32_t>(b, 4);
    for (int k = 0; k < 3; ++k) {
        out.force[k] = get<double>(b, 8 + 8 * k);
        out.torque[k] = get<double>(b, 32 + 8 * k);
    }
    out.flags = get<std::uint32_t>(b, 56);
    return true;
}

}  // namespace coiffure
