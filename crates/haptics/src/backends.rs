//! Device backends: scripted (a tool path, for tests and experiments), virtual (readings pushed from another
//! thread without locks, e.g. the browser's mouse), and UDP (a program on a machine with a real device streams
//! poses and receives forces; see docs/protocol.md and [`crate::udp`]).

use crate::device::{DeviceCommand, DeviceReading, HapticDevice};
use triple_buffer::{triple_buffer, Input, Output};

/// A device that replays a path: `path(t)` gives the reading at time t, or `None` when the path has ended.
/// Every command written is kept, so a test or experiment can read the forces back.
pub struct ScriptedDevice {
    path: Box<dyn FnMut(f64) -> Option<DeviceReading> + Send>,
    /// Commands received, in order.
    pub commands: Vec<DeviceCommand>,
}

impl ScriptedDevice {
    /// A scripted device following `path`.
    pub fn new(path: impl FnMut(f64) -> Option<DeviceReading> + Send + 'static) -> Self {
        Self { path: Box::new(path), commands: Vec::new() }
    }
}

impl HapticDevice for ScriptedDevice {
    fn read(&mut self, time: f64) -> Option<DeviceReading> {
        (self.path)(time)
    }
    fn write(&mut self, command: &DeviceCommand) {
        self.commands.push(*command);
    }
}

/// The haptic-thread side of a virtual device: reads the latest pushed reading, publishes commands.
/// Both directions go through wait-free triple buffers: neither side ever blocks.
pub struct VirtualDevice {
    readings: Output<Option<DeviceReading>>,
    commands: Input<DeviceCommand>,
}

/// The other thread's side of a virtual device: pushes readings, reads the latest command.
pub struct VirtualHandle {
    readings: Input<Option<DeviceReading>>,
    commands: Output<DeviceCommand>,
}

/// A connected pair: the device for the haptic loop and the handle for the thread that drives it.
pub fn virtual_device() -> (VirtualDevice, VirtualHandle) {
    let (r_in, r_out) = triple_buffer(&None);
    let (c_in, c_out) = triple_buffer(&DeviceCommand::default());
    (VirtualDevice { readings: r_out, commands: c_in }, VirtualHandle { readings: r_in, commands: c_out })
}

impl HapticDevice for VirtualDevice {
    fn read(&mut self, _time: f64) -> Option<DeviceReading> {
        *self.readings.read()
    }
    fn write(&mut self, command: &DeviceCommand) {
        self.commands.write(*command);
    }
}

impl VirtualHandle {
    /// Publishes a reading (the newest wins).
    pub fn push(&mut self, reading: DeviceReading) {
        self.readings.write(Some(reading));
    }
    /// The latest command the haptic loop sent.
    pub fn latest(&mut self) -> DeviceCommand {
        *self.commands.read()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn virtual_device_passes_the_latest_values_across_threads() {
        let (mut dev, mut handle) = virtual_device();
        assert!(dev.read(0.0).is_none());
        let t = std::thread::spawn(move || {
            for i in 0..1000 {
                handle.push(DeviceReading { time: i as f64, position: Vector3::new(i as f64, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 0 });
            }
            handle
        });
        let mut handle = t.join().unwrap();
        assert_eq!(dev.read(0.0).unwrap().position.x, 999.0, "the newest reading wins");
        dev.write(&DeviceCommand { force: Vector3::new(0.5, 0.0, 0.0), torque: Vector3::zeros() });
        assert_eq!(handle.latest().force.x, 0.5);
    }
}
