//! What a record says about the session it recorded, beyond its steps: the built-in scene's options and the
//! session settings `coiffure serve`'s options change, so that `coiffure replay` rebuilds the same scene and
//! cores without being told (a device session's replay needs the device's input kind and profile to give its
//! forces again). Kept in the header chunk as TOML text: a field a later version adds is ignored by an older
//! reader and defaults when missing.

use crate::params::{InputKind, SessionParams};
use crate::scene::SceneOptions;
use haptics::device::DeviceProfile;
use serde::{Deserialize, Serialize};

/// The recorded session's scene and settings (defaults: `coiffure serve`'s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RecordSettings {
    /// Render strands of the built-in hairstyle.
    pub render_strands: usize,
    /// Vertices per render strand.
    pub render_vertices: usize,
    /// Guide strands.
    pub guides: usize,
    /// Super-Helix segments per guide.
    pub segments: usize,
    /// Centreline samples per guide.
    pub samples: usize,
    /// Hair length, m.
    pub length: f64,
    /// Curliness in [0, 1].
    pub curliness: f64,
    /// Lattice cell size, m.
    pub cell: f64,
    /// Hair type name.
    pub hair_type: String,
    /// Random seed of the hairstyle.
    pub seed: u64,
    /// Where the readings came from: "pointer" (the mouse) or "device".
    pub input: String,
    /// Device profile name (`DeviceProfile::by_name`).
    pub device_profile: String,
    /// `SessionParams::hairs_per_render_strand`.
    pub hairs_per_render_strand: f64,
    /// `HapticParams::max_proxy_lag`, m.
    pub max_proxy_lag: f64,
    /// Global step rate, Hz.
    pub global_rate_hz: f64,
    /// Device loop rate, Hz (`SessionParams::device_rate_hz`: the length of the recorded device steps).
    pub device_rate_hz: f64,
    /// `HapticParams::entanglement`: the combing law. False when missing: records written before it was on by
    /// default (2026-11-30) combed without it.
    #[serde(default)]
    pub entanglement: bool,
}

impl Default for RecordSettings {
    fn default() -> Self {
        Self::of(&SceneOptions::default(), &SessionParams::default())
    }
}

impl RecordSettings {
    /// The settings of a session on the built-in scene of `scene` with `params`.
    pub fn of(scene: &SceneOptions, params: &SessionParams) -> Self {
        Self {
            render_strands: scene.render_strands,
            render_vertices: scene.render_vertices,
            guides: scene.guides,
            segments: scene.segments,
            samples: scene.samples,
            length: scene.length,
            curliness: scene.curliness,
            cell: scene.cell,
            hair_type: scene.hair_type.clone(),
            seed: scene.seed,
            input: match params.input {
                InputKind::Pointer => "pointer",
                InputKind::Device => "device",
            }
            .into(),
            device_profile: params.profile.name.into(),
            hairs_per_render_strand: params.hairs_per_render_strand,
            max_proxy_lag: params.haptic.max_proxy_lag,
            global_rate_hz: params.global_rate_hz,
            device_rate_hz: params.device_rate_hz,
            entanglement: params.haptic.entanglement,
        }
    }

    /// The built-in scene's options.
    pub fn scene_options(&self) -> SceneOptions {
        SceneOptions {
            render_strands: self.render_strands,
            render_vertices: self.render_vertices,
            guides: self.guides,
            segments: self.segments,
            samples: self.samples,
            length: self.length,
            curliness: self.curliness,
            cell: self.cell,
            hair_type: self.hair_type.clone(),
            seed: self.seed,
            ..SceneOptions::default()
        }
    }

    /// The session's parameters (the others at their defaults) at the haptic rate `rate_hz`; an unknown input
    /// kind or device profile is an error naming it.
    pub fn session_params(&self, rate_hz: f64) -> Result<SessionParams, String> {
        let mut p = SessionParams::default();
        p.input = match self.input.as_str() {
            "pointer" => InputKind::Pointer,
            "device" => InputKind::Device,
            k => return Err(format!("input {k:?} (pointer or device)")),
        };
        p.profile = DeviceProfile::by_name(&self.device_profile).ok_or_else(|| format!("device profile {:?}", self.device_profile))?;
        p.hairs_per_render_strand = self.hairs_per_render_strand;
        p.haptic.max_proxy_lag = self.max_proxy_lag;
        p.global_rate_hz = self.global_rate_hz;
        p.device_rate_hz = self.device_rate_hz;
        p.haptic.entanglement = self.entanglement;
        p.haptic_rate_hz = rate_hz;
        Ok(p)
    }

    /// As TOML text.
    pub fn to_text(&self) -> String {
        toml::to_string(self).expect("settings of numbers and strings serialise")
    }

    /// From TOML text; the error says what is wrong.
    pub fn from_text(text: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_round_trip_and_rebuild_the_session() {
        // Every field the server's options change comes back; missing ones default.
        let scene = SceneOptions { render_strands: 5000, guides: 60, hair_type: "asian".into(), seed: 7, ..SceneOptions::default() };
        let mut params = SessionParams { input: InputKind::Device, profile: DeviceProfile::by_name("omega3").unwrap(), hairs_per_render_strand: 20.0, global_rate_hz: 50.0, device_rate_hz: 10_000.0, ..SessionParams::default() };
        params.haptic.max_proxy_lag = 0.3;
        let s = RecordSettings::of(&scene, &params);
        let back = RecordSettings::from_text(&s.to_text()).unwrap();
        assert_eq!(back, s);
        let o = back.scene_options();
        assert_eq!((o.render_strands, o.guides, o.hair_type.as_str(), o.seed), (5000, 60, "asian", 7));
        let p = back.session_params(2000.0).unwrap();
        assert_eq!(p, SessionParams { haptic_rate_hz: 2000.0, ..params });
        assert_eq!(RecordSettings::from_text("").unwrap(), RecordSettings { entanglement: false, ..RecordSettings::default() });
        // The combing law comes back both ways; a record written before the field existed combed without it.
        for law in [false, true] {
            let mut q = params;
            q.haptic.entanglement = law;
            let text = RecordSettings::of(&scene, &q).to_text();
            assert!(text.contains(&format!("entanglement = {law}")), "{text}");
            assert_eq!(RecordSettings::from_text(&text).unwrap().session_params(1000.0).unwrap().haptic.entanglement, law);
        }
        let old: String = s.to_text().lines().filter(|l| !l.starts_with("entanglement")).map(|l| format!("{l}\n")).collect();
        assert!(!RecordSettings::from_text(&old).unwrap().session_params(1000.0).unwrap().haptic.entanglement);
        // Every device profile comes back by its name.
        for profile in [DeviceProfile::PHANTOM_OMNI, DeviceProfile::PHANTOM_DESKTOP, DeviceProfile::OMEGA3, DeviceProfile::PHANTOM_PREMIUM_6DOF, DeviceProfile::MOUSE] {
            let s = RecordSettings::of(&scene, &SessionParams { profile, ..params });
            assert_eq!(s.session_params(1000.0).unwrap().profile, profile);
        }
        assert!(RecordSettings::from_text("guides = -3").unwrap_err().contains("guides"));
        assert!(RecordSettings { input: "joystick".into(), ..s }.session_params(1000.0).unwrap_err().contains("joystick"));
    }
}
