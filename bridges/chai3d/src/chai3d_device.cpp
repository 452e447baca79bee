// The first device found by CHAI3D's cHapticDeviceHandler (Phantom through OpenHaptics, Force Dimension
// omega and delta, Novint Falcon, ...).
#include "device.h"

// The device layer only (the bridge draws nothing): builds against a whole CHAI3D or its device sources.
#include "devices/CHapticDeviceHandler.h"

namespace coiffure {
namespace {

class Chai3dDevice : public Device {
public:
    bool open(std::string& error) override {
        handler_ = std::make_unique<chai3d::cHapticDeviceHandler>();
        if (handler_->getNumDevices() == 0 || !handler_->getDevice(device_, 0) || !device_) {
            error = "CHAI3D found no haptic device (is it plugged in and its driver running?)";
            return false;
        }
        if (!device_->open()) {
            error = "CHAI3D could not open the device";
            return false;
        }
        device_->calibrate();
        auto s = device_->getSpecifications();
        info_ = DeviceInfo{s.m_manufacturerName + " " + s.m_modelName, s.m_maxLinearForce, s.m_maxAngularTorque, s.m_workspaceRadius};
        return true;
    }
    void close() override {
        if (device_) {
            device_->setForce(chai3d::cVector3d(0, 0, 0));
            device_->close();
        }
    }
    DeviceInfo info() const override { return info_; }
    void read(double, std::array<double, 3>& p, std::array<double, 9>& r, std::uint32_t& buttons) override {
        chai3d::cVector3d x;
        chai3d::cMatrix3d m;
        device_->getPosition(x);
        device_->getRotation(m);
        p = {x.x(), x.y(), x.z()};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r[3 * i + j] = m(i, j);
        unsigned int switches = 0;
        device_->getUserSwitches(switches);
        buttons = switches;
    }
    void set_force_and_torque(const std::array<double, 3>& f, const std::array<double, 3>& t) override {
        // CHAI3D's call for force, torque and gripper force (0: the gripper gets none); a 3-DOF device applies the force.
        device_->setForceAndTorqueAndGripperForce(chai3d::cVector3d(f[0], f[1], f[2]), chai3d::cVector3d(t[0], t[1], t[2]), 0.0);
    }

private:
    std::unique_ptr<chai3d::cHapticDeviceHandler> handler_;
    chai3d::cGenericHapticDevicePtr device_;
    DeviceInfo info_;
};

}  // namespace

std::unique_ptr<Device> make_device() { return std::make_unique<Chai3dDevice>(); }

}  // namespace coiffure
