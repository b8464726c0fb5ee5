//! Building the renderer's per-frame snapshot from the scene and the playback state.

use super::glyphs::{tool_glyph, REGION_RGB};
use crate::math::{Aabb, Vec3, Vec4};
use crate::render::{Frame, Light, Material, Stage};
use crate::scene::{Attachment, Scene, SceneLight, SceneToolShape};
use crate::tool::ToolShape;

/// The glyphs of the lattices `playback` has open and whose scene shows them, and of the
/// lattice held open at the desk or in the headset (placed with its part).
pub fn lattice_glyphs(playback: &super::playback::Playback<'_>) -> Vec<crate::render::ToolGlyph> {
    let iso = playback.field().iso() as f64;
    let mut glyphs: Vec<_> = playback
        .open_lattices()
        .filter(|(scene, _)| scene.show)
        .flat_map(|(scene, lattice)| {
            let mut glyphs = super::glyphs::lattice_glyphs(lattice.volume(), iso);
            if let Some(k) = scene.slice {
                glyphs.extend(super::glyphs::lattice_slice_glyphs(lattice.volume(), k, iso));
            }
            // Drawn in its part's frame.
            let frame = part_matrix(playback, scene.part);
            for g in &mut glyphs {
                g.model = frame * g.model;
            }
            glyphs
        })
        .collect();
    if let Some(held) = playback.held_lattice() {
        glyphs.extend(held.glyphs(iso, part_matrix(playback, held.part())));
    }
    glyphs
}

/// The box of the active part of a sculpt of several parts, turned and scaled with it (none
/// for one part, or an empty one).
pub fn part_glyph(
    playback: &super::playback::Playback<'_>,
    colour: Vec4,
) -> Option<crate::render::ToolGlyph> {
    let parts = playback.assembly();
    let (layouts, active) = (parts.parts(), parts.active());
    if layouts.len() < 2 {
        return None;
    }
    let bounds = crate::parts::local_bounds(parts.field(playback.field(), active));
    part_glyph_of(bounds, &layouts[active].placement, colour)
}

fn part_glyph_of(
    bounds: Aabb,
    placement: &crate::parts::Placement,
    colour: Vec4,
) -> Option<crate::render::ToolGlyph> {
    if bounds.is_empty() {
        return None;
    }
    let local = crate::math::Mat4::from_scale_rotation_translation(
        0.5 * bounds.size(),
        crate::math::Quat::IDENTITY,
        bounds.centre(),
    );
    Some(crate::render::ToolGlyph {
        shape: crate::render::GlyphShape::Box,
        model: placement.to_matrix() * local,
        colour,
    })
}

/// The colour the active part's box is drawn in: a faint blue.
pub const PART_COLOUR: Vec4 = Vec4::new(0.35, 0.6, 1.0, 0.12);

/// The colour regions being carried are drawn in: a faint warm yellow.
pub const REGION_COLOUR: Vec4 = Vec4::new(REGION_RGB[0], REGION_RGB[1], REGION_RGB[2], 0.2);

/// The colour of the box selected for the region tools: the regions' yellow, fainter.
pub const SELECTION_COLOUR: Vec4 = Vec4::new(REGION_RGB[0], REGION_RGB[1], REGION_RGB[2], 0.1);

/// The regions the scene's region tools are carrying now, and the region the desk or the
/// headset holds (placed with its part), with their images, where the hand has taken them.
pub fn region_glyphs(playback: &super::playback::Playback<'_>) -> Vec<crate::render::ToolGlyph> {
    // Each drawn in its part's frame.
    let glyph = |part: usize, r: &crate::parts::Region, colour: Vec4| {
        let g = tool_glyph(&r.shape, r.frame.pose, r.frame.scale, colour);
        crate::render::ToolGlyph { model: part_matrix(playback, part) * g.model, ..g }
    };
    let carried = |part: usize, drag: &crate::parts::RegionDrag| {
        drag.carried_regions().iter().map(|r| glyph(part, r, REGION_COLOUR)).collect::<Vec<_>>()
    };
    let scene =
        playback.moving_regions().filter(|(sr, _)| sr.show).flat_map(|(sr, drag)| carried(sr.part, drag));
    let held = playback.held_region().into_iter().flat_map(|held| carried(held.part(), held.drag()));
    // The box selected, fainter, unless it is being carried.
    let selected = playback
        .selection()
        .filter(|_| playback.held_region().is_none())
        .map(|(part, r)| glyph(part, r, SELECTION_COLOUR));
    scene.chain(held).chain(selected).collect()
}

/// Part `part`'s frame: its placement's matrix (the identity for a part at rest).
fn part_matrix(playback: &super::playback::Playback<'_>, part: usize) -> crate::math::Mat4 {
    playback.assembly().frame_of(part).map_or(crate::math::Mat4::IDENTITY, |p| p.to_matrix())
}

/// The glyphs of the symmetry `playback`'s strokes act through, over the scene's initial
/// clay (or its stage, or 20 cm about the symmetry's centre), and the images of the scripted
/// hands' tools; none without symmetry.
pub fn symmetry_glyphs(playback: &super::playback::Playback<'_>) -> Vec<crate::render::ToolGlyph> {
    let symmetry = playback.symmetry();
    if symmetry.is_none() {
        return Vec::new();
    }
    let scene = playback.scene();
    let clay = scene
        .clay
        .iter()
        .map(|c| scene.parts[c.part].placement.world_box(c.solid.bounds()))
        .reduce(|a, b| a.union(&b));
    let around = clay
        .map(|b| b.expanded(0.15 * b.size().max_element()))
        .or(scene.stage.map(|s| Aabb { min: s.min_m, max: s.max_m }))
        .unwrap_or(Aabb::from_centre_half(symmetry.frame.position_m, Vec3::splat(0.1)));
    let mut glyphs = super::glyphs::symmetry_glyphs(symmetry, around);
    // The scripted hands' tools at their images, fainter than the tools themselves.
    for (tool, pose) in playback.hands() {
        let t = &scene.tools[tool];
        let colour = Vec4::from(t.colour).truncate().extend(0.5 * t.glyph_opacity);
        for image in playback.images().iter().skip(1) {
            glyphs.push(tool_glyph(&scene_tool_shape(&t.shape), image.pose(&pose).0, t.scale, colour));
        }
    }
    glyphs
}

/// Resolves the scene's lights into world space for the current viewer.
pub fn world_lights(scene: &Scene) -> Vec<Light> {
    // The viewer's frame is the centre eye's: view space → world space.
    let viewer_to_world = scene.rig.centre_view().inverse();
    scene
        .lights
        .iter()
        .map(|l| match *l {
            SceneLight::Directional { direction, radiance, attached_to } => Light::Directional {
                direction: match attached_to {
                    Attachment::Scene => direction,
                    Attachment::Viewer => viewer_to_world.transform_vector3(direction),
                },
                radiance,
            },
            SceneLight::Point { position_m, radiance, attached_to } => Light::Point {
                position_m: match attached_to {
                    Attachment::Scene => position_m,
                    Attachment::Viewer => viewer_to_world.transform_point3(position_m),
                },
                radiance,
            },
        })
        .collect()
}

/// The shape a scene tool is drawn with: its own, or for a freeform tool (whose samples are
/// copied only when playback starts) the box it is copied from, which its glyph spans.
fn scene_tool_shape(shape: &SceneToolShape) -> ToolShape {
    match shape {
        SceneToolShape::Shape(s) => s.clone(),
        SceneToolShape::Freeform { min_m, max_m } => {
            ToolShape::Solid(crate::tool::Solid::Box { half_m: 0.5 * (*max_m - *min_m) })
        }
    }
}

/// The frame to draw: views for the output's aspect, lights, material, stage, and a glyph for
/// each tool held in `hands` (`(tool index, pose)` pairs) when `show_tools`.
pub fn build_frame(scene: &Scene, hands: &[(usize, crate::math::Pose)], show_tools: bool) -> Frame {
    let aspect = scene.output.width_px as f32 / scene.output.height_px as f32;
    let tools = if show_tools {
        hands
            .iter()
            .map(|&(tool, pose)| {
                let t = &scene.tools[tool];
                let colour = Vec4::from(t.colour).truncate().extend(t.glyph_opacity);
                tool_glyph(&scene_tool_shape(&t.shape), pose, t.scale, colour)
            })
            .collect()
    } else {
        Vec::new()
    };
    let m = &scene.material;
    Frame {
        views: scene.rig.views(aspect),
        lights: world_lights(scene),
        material: Material {
            shininess: m.shininess,
            specular: m.specular,
            reflectivity: m.reflectivity,
            ambient: m.ambient,
        },
        tools,
        controllers: Vec::new(),
        stage: scene.stage.map(|s| Stage { min_m: s.min_m, max_m: s.max_m, colour: s.colour }),
        show_environment: scene.environment.show,
        background: scene.environment.background,
        hud: Vec::new(),
        panel: None,
        floating_window: crate::stereo::floating::FloatingWindow::NONE,
        eye_marks: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewer_lights_follow_the_viewer() {
        let scene = Scene::parse(
            "[camera]\neye_m = [1.0, 0.0, 0.0]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, -1.0]\nattached_to = \"viewer\"\n\
             [[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, -1.0]\n",
            "l",
            None,
        )
        .unwrap();
        let lights = world_lights(&scene);
        let Light::Directional { direction, .. } = lights[0] else { panic!() };
        assert!(
            (direction - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-5,
            "shines where the viewer looks: {direction}"
        );
        let Light::Directional { direction, .. } = lights[1] else { panic!() };
        assert!((direction - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
    }

    #[test]
    fn glyphs_carry_the_tool_size_and_opacity() {
        let scene = Scene::default_scene();
        let pose = crate::math::Pose { position_m: Vec3::new(0.1, 0.0, 0.0), ..Default::default() };
        let f = build_frame(&scene, &[(0, pose)], true);
        let g = f.tools[0];
        let edge = g.model.transform_point3(Vec3::X);
        assert!((edge.x - (0.1 + scene.tools[0].half_extents_m().x)).abs() < 1e-6);
        assert_eq!(g.colour.w, scene.tools[0].glyph_opacity);
        assert!(build_frame(&scene, &[(0, pose)], false).tools.is_empty());
    }
}
