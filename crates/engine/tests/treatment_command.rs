//! The viewer's treatment selector reaches the live session's law: `Command::SetTreatment` sets the tool-hair
//! friction the haptic core uses (and reports in its snapshot, the FRAME's) to the hair type's coefficient times
//! the treatment's factor (`tools::treatment::Treatment::friction_factor`, dry hair), for every hair type and
//! treatment, at combing ease 0 and 0.5; a later SetHair keeps the treatment.

use engine::session::{Command, GlobalCore, HapticCore, HapticParams, HapticSnapshot, Scene, SceneOptions, SessionParams};
use std::sync::Arc;
use strand::HairType;
use tools::treatment::{Contact, Treatment};

#[test]
fn every_treatment_sets_the_sessions_tool_friction_by_the_one_law() {
    let scene = Arc::new(Scene::builtin(&SceneOptions { render_strands: 500, guides: 30, ..SceneOptions::default() }).unwrap());
    let params = SessionParams::default();
    let lattice = GlobalCore::new(scene.clone(), &params).snapshot();
    let mut core = HapticCore::new(scene, params).unwrap();
    let mut snap = HapticSnapshot::default();
    let mut worst = 0.0f64;
    for (i, hair) in HairType::ALL.iter().enumerate() {
        for ease in [0.0, 0.5] {
            for t in Treatment::ALL {
                core.apply(&Command::SetTreatment(t));
                core.apply(&Command::SetHair { hair_type: i as u8, curliness: 0.0, combing_ease: ease });
                core.snapshot(&lattice, 1e-3, &mut snap);
                let want = HapticParams::default().combing_friction(hair.friction_coefficient() * t.friction_factor(Contact::Tool, 0.0), ease);
                assert_eq!(snap.treatment, t, "{} {t}", hair.name);
                let rel = (snap.tool_friction - want).abs() / want;
                worst = worst.max(rel);
                assert!(rel < 1e-12, "{} {t} ease {ease}: {} vs {want}", hair.name, snap.tool_friction);
            }
        }
    }
    println!("{} hair types x 4 treatments x 2 eases: worst relative difference {worst:.1e}", HairType::ALL.len());
}
