// A simulated device (no CHAI3D, no hardware): a 45 g end-effector with 0.05 N s/m of friction, pulled by a
// hand (300 N/m, 3 N s/m) along a vertical stroke 1 cm in front of the workspace's centre (CHAI3D frame:
// -x, away from the user), 3 cm up and down at 0.5 Hz; the force the bridge sets acts on it. The primary
// button is held. Semi-implicit Euler between reads.
#include "device.h"

#include <cmath>

namespace coiffure {
namespace {

class SimDevice : public Device {
public:
    bool open(std::string&) override { return true; }
    void close() override {}
    DeviceInfo info() const override { return DeviceInfo{"simulated device (45 g, Phantom Omni limits, 3-DOF)", 3.3, 0.0, 0.06}; }
    void read(double t, std::array<double, 3>& p, std::array<double, 9>& r, std::uint32_t& buttons) override {
        const double kPi = 3.14159265358979323846;
        const double m = 0.045, b = 0.05, k_hand = 300.0, b_hand = 3.0;
        std::array<double, 3> target{-0.01, 0.0, 0.03 * std::cos(2.0 * kPi * 0.5 * t)};
        std::array<double, 3> target_v{0.0, 0.0, -0.03 * 2.0 * kPi * 0.5 * std::sin(2.0 * kPi * 0.5 * t)};
        if (started_) {
            double dt = t - last_;
            if (dt > 0.0 && dt < 0.05) {
                for (int k = 0; k < 3; ++k) {
                    double a = (k_hand * (target[k] - x_[k]) + b_hand * (target_v[k] - v_[k]) - b * v_[k] + f_[k]) / m;
                    v_[k] += a * dt;
                    x_[k] += v_[k] * dt;
                }
            }
        } else {
            x_ = target;
            started_ = true;
        }
        last_ = t;
        p = x_;
        r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        buttons = 1;
    }
    void set_force_and_torque(const std::array<double, 3>& f, const std::array<double, 3>&) override { f_ = f; }

private:
    bool started_ = false;
    double last_ = 0.0;
    std::array<double, 3> x_{}, v_{}, f_{};
};

}  // namespace

std::unique_ptr<Device> make_device() { return std::make_unique<SimDevice>(); }

}  // namespace coiffure
