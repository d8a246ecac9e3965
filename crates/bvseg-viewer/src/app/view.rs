//! The 3D view: the orbit camera's input, and the scene handed to the glow renderer in a paint
//! callback.
use std::sync::Arc;

use eframe::egui::{self, Color32};
use eframe::egui_glow;

use super::{SceneKey, ViewerApp};
use crate::animation::{self, Player};
use crate::render::{Frame, Renderer};
use crate::scene::{self, Geometry, VolumeStyle};

impl ViewerApp {
    fn scene_geometry(&mut self) -> Option<(u64, Arc<Geometry>)> {
        let model = self.model.as_ref()?;
        let snap = self.shown_snapshot();
        let pose = self.player.as_ref().and_then(Player::pose);
        let key = SceneKey {
            model: self.model_id,
            run: self.run_id,
            snapshot: self.shown_step(),
            final_colours: self.showing_result(),
            pose,
            selected: self.selected_part,
            display: self.display,
        };
        if let Some((k, generation, g)) = &self.scene {
            if *k == key {
                return Some((*generation, g.clone()));
            }
        }
        let rig = model.mesh.rig();
        let posed = pose.and_then(|p| {
            let skin = rig?.skin.as_ref()?;
            Some((skin, skin.poses.get(p)?))
        });
        let g = match posed {
            None => scene::build(&model.geometry, snap, &[], self.selected_part, self.display),
            Some((skin, pose)) => {
                let mesh = model.geometry.posed(skin, pose);
                // Only the result's volumes have bones (and enclose the posed surface): the
                // volumes of a step before it stay hidden in a pose.
                let moves = match (self.volumes_follow(), rig) {
                    (Some(bones), Some(rig)) => animation::motions(bones, &rig.skeleton, pose),
                    _ => Vec::new(),
                };
                let mut display = self.display;
                if moves.is_empty() {
                    display.volumes = VolumeStyle::Hidden;
                }
                scene::build(&mesh, snap, &moves, self.selected_part, display)
            }
        };
        let g = Arc::new(g);
        self.generation += 1;
        self.scene = Some((key, self.generation, g.clone()));
        Some((self.generation, g))
    }

    /// The bones of the volumes shown, when they follow a character's animation: the shown
    /// step is the result's final one, on a mesh with sampled poses.
    pub(super) fn volumes_follow(&self) -> Option<Vec<Option<usize>>> {
        let skin = self.model.as_ref()?.mesh.rig()?.skin.as_ref()?;
        if skin.poses.is_empty() || !self.showing_result() {
            return None;
        }
        Some(self.result()?.parts.iter().map(|p| p.bone).collect())
    }

    pub(super) fn view(&mut self, ui: &mut egui::Ui) {
        let (rect, response) =
            ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        self.view_rect = Some(rect);
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_rgb(32, 34, 40));
        let shift = ui.input(|i| i.modifiers.shift);
        let d = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && !shift {
            self.camera.orbit(d.x, d.y);
        } else if response.dragged() {
            self.camera.pan(d.x, d.y, rect.height());
        }
        if response.hovered() {
            let (scroll, zoom) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
            self.camera.zoom(zoom * (scroll * 0.002).exp());
        }
        if response.double_clicked() {
            self.camera.reset();
        }
        if let Some((generation, geometry)) = self.scene_geometry() {
            let frame = Arc::new(Frame {
                generation,
                geometry,
                view_projection: self.camera.view_projection(rect.aspect_ratio()),
                light: (self.camera.eye() - self.camera.target).normalize_or_zero(),
            });
            let gpu = self.gpu.clone();
            let callback = egui_glow::CallbackFn::new(move |_info, painter| {
                let Ok(mut gpu) = gpu.lock() else {
                    return;
                };
                let r = gpu.get_or_insert_with(|| Renderer::new(painter.gl()));
                if let Ok(r) = r {
                    r.paint(painter.gl(), &frame);
                }
            });
            painter.add(egui::PaintCallback {
                rect,
                callback: Arc::new(callback),
            });
        }
        let note = |text: &str| {
            painter.text(
                rect.center_top() + egui::vec2(0.0, 12.0),
                egui::Align2::CENTER_TOP,
                text,
                egui::FontId::proportional(14.0),
                Color32::from_gray(200),
            );
        };
        if let Ok(gpu) = self.gpu.lock() {
            if let Some(Err(e)) = gpu.as_ref() {
                note(e);
            }
        }
        if self.model.is_none() {
            note("Pick a mesh in the Mesh menu, or drop a mesh file here");
        }
        if ui.ctx().input(|i| !i.raw.hovered_files.is_empty()) {
            painter.rect_filled(rect, 0.0, Color32::from_black_alpha(120));
            note("Drop to load");
        }
    }
}
