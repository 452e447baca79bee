//! Haptic devices: the [`HapticDevice`] trait a backend implements. What a device reports and accepts is in
//! [`crate::reading`], its limits in [`crate::profile`] (both re-exported here).

pub use crate::profile::DeviceProfile;
pub use crate::reading::{DeviceCommand, DeviceReading};
use crate::local_model::ModelFeed;

/// A device driven at the haptic rate.
pub trait HapticDevice: Send {
    /// The latest reading, or `None` when the device has no new data (scripted path ended, connection lost).
    fn read(&mut self, time: f64) -> Option<DeviceReading>;
    /// Sends a force and torque to the device.
    fn write(&mut self, command: &DeviceCommand);
    /// A feed through which the device loop gives the device each new local force model, for a device that
    /// forwards it (the UDP device's version-2 answers); None (the default) for the others.
    fn model_feed(&mut self) -> Option<ModelFeed> {
        None
    }
}

/// A boxed device is a device (the live session holds the mouse's or a UDP device behind one type).
impl<T: HapticDevice + ?Sized> HapticDevice for Box<T> {
    fn read(&mut self, time: f64) -> Option<DeviceReading> {
        (**self).read(time)
    }
    fn write(&mut self, command: &DeviceCommand) {
        (**self).write(command)
    }
    fn model_feed(&mut self) -> Option<ModelFeed> {
        (**self).model_feed()
    }
}
