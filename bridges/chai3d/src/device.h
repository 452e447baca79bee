// The device the bridge drives: CHAI3D's first device (chai3d_device.cpp) or a simulated one
// (sim_device.cpp, -DCOIFFURE_SIMULATED_DEVICE=ON). Everything in CHAI3D's frame: x towards the user, y to
// the right, z up; m, N.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>

namespace coiffure {

struct DeviceInfo {
    std::string name;
    double max_force = 0.0;         // N
    double max_torque = 0.0;        // N m (0: a 3-DOF device, force only)
    double workspace_radius = 0.0;  // m
};

class Device {
public:
    virtual ~Device() = default;
    // Opens and calibrates the device; false with `error` set if it cannot.
    virtual bool open(std::string& error) = 0;
    virtual void close() = 0;
    virtual DeviceInfo info() const = 0;
    // End-effector position (m), rotation (row-major, tool to device frame) and buttons at time `t` (s).
    virtual void read(double t, std::array<double, 3>& position, std::array<double, 9>& rotation, std::uint32_t& buttons) = 0;
    // Force (N) and torque (N m) on the hand until the next call (a 3-DOF device applies the force only).
    virtual void set_force_and_torque(const std::array<double, 3>& force, const std::array<double, 3>& torque) = 0;
    void set_force(const std::array<double, 3>& force) { set_force_and_torque(force, {0, 0, 0}); }
};

// The first device CHAI3D finds, or the simulated one.
std::unique_ptr<Device> make_device();

}  // namespace coiffure
