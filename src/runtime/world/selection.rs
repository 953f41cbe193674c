//! One instance looked at closely: picked by a ray through a pixel, and what its levels of
//! detail are (Unity's LOD Group strip: each level as the band of screen heights it is drawn
//! at, with its triangles) and which one it shows now.

use super::World;
use crate::scene::{LodDraw, ScreenProjection};
use glam::{Vec2, Vec3};

/// A level of the picked instance's model as selection sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    pub level: u8,
    /// The model's screen height (pixels) from which it is drawn: it shows at this height and
    /// below, down to the next band's (0 for the last).
    pub from_px: f32,
    /// Its triangles, where it is a mesh on the GPU (an impostor is one quad).
    pub triangles: Option<u64>,
    /// The character's animated impostor, appended after its meshes.
    pub impostor: bool,
}

/// What the panel says of a picked instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspected {
    pub instance: usize,
    pub model: usize,
    pub name: String,
    /// What it draws now (left side), and the level it mostly shows.
    pub draw: LodDraw,
    pub level: u8,
    /// The model's height on screen now, pixels (its bounds' height, scaled).
    pub height_px: f32,
    /// The shown level's error projected now, pixels.
    pub error_px: f32,
    pub bands: Vec<Band>,
}

impl World {
    /// The bounding sphere (centre, radius) of instance `i` as last selected.
    pub fn instance_sphere(&self, i: usize) -> Option<(Vec3, f32)> {
        let inst = self.instances.get(i)?;
        let bounds = &self.bakes.get(inst.model)?.bounds;
        let t = &inst.transform;
        let scale = t.matrix3.x_axis.length().max(t.matrix3.y_axis.length());
        Some((
            t.transform_point3(bounds.center() + inst.travel),
            bounds.diagonal() * 0.5 * scale,
        ))
    }

    /// The instance under `ndc` (normalised device coordinates of the view, x right and y up,
    /// −1..1) of a view `aspect` wide for 1 high: the nearest whose bounding sphere the ray
    /// through it enters. Patches and culled instances count as they were last selected.
    pub fn pick(&self, ndc: Vec2, aspect: f32) -> Option<usize> {
        let inverse = (self.camera.proj(aspect) * self.camera.view()).inverse();
        let near = inverse.project_point3(ndc.extend(0.0));
        let far = inverse.project_point3(ndc.extend(0.5));
        let dir = (far - near).normalize_or_zero();
        if dir == Vec3::ZERO {
            return None;
        }
        (0..self.instances.len())
            .filter_map(|i| {
                let (c, r) = self.instance_sphere(i)?;
                // Where the ray enters the sphere, if it does.
                let along = (c - near).dot(dir);
                let miss = (c - near).length_squared() - along * along;
                (miss <= r * r).then(|| (i, along - (r * r - miss).sqrt()))
            })
            .filter(|&(_, t)| t > 0.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// Instance `i` as the left side shows it in a view `height` pixels high: its model, what
    /// it draws, its size and error on screen, and its model's levels as bands of screen
    /// height at the current tolerance.
    pub fn inspect(&self, i: usize, height: u32) -> Option<Inspected> {
        let inst = self.instances.get(i)?;
        let m = inst.model;
        let bake = self.bakes.get(m)?;
        let slot = self.lod.method.index();
        let lod = self.lod.model(m, slot)?;
        let draw = self.lod.draws[0].get(i).copied()?;
        let level = draw.nearest_level();
        let (centre, radius) = self.instance_sphere(i)?;
        let (near, _) = self.camera.near_far();
        let screen =
            ScreenProjection::new(self.camera.eye(), self.camera.fov_y, height as f32, near);
        let distance = screen.sphere_distance(centre, radius);
        let scale = inst.transform.matrix3.y_axis.length();
        let model_height = bake.bounds.size().y.max(1e-6);
        let height_px = screen.projected(model_height * scale, distance);
        let error = lod.errors.get(level as usize).copied().unwrap_or(0.0);
        let tolerance = self.lod.policy.tolerance_px.max(1e-3);
        let set = self
            .renderer
            .characters()
            .get(m)
            .and_then(|c| c.set(slot).or_else(|| c.set(0)));
        let meshes = set.map_or(1, |s| s.levels.len());
        let bands = lod
            .errors
            .iter()
            .enumerate()
            .map(|(k, &e)| Band {
                level: k as u8,
                // Level k is drawn where its error projects within the tolerance: while the
                // model is at most tolerance · height / e pixels high.
                from_px: if e > 0.0 {
                    tolerance * model_height / e
                } else {
                    f32::INFINITY
                },
                triangles: set
                    .and_then(|s| s.levels.get(k))
                    .map(|l| l.index_count as u64 / 3),
                impostor: k >= meshes && self.lod.impostor_model(m, slot).is_some(),
            })
            .collect();
        Some(Inspected {
            instance: i,
            model: m,
            name: bake.name.clone(),
            draw,
            level,
            height_px,
            error_px: screen.projected(error * scale, distance),
            bands,
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};

    /// The ray through the centre of the view hits what the camera looks at.
    #[test]
    fn the_ray_through_the_centre_meets_the_target() {
        let c = crate::scene::Camera::new(Vec3::new(1.0, 2.0, -3.0), 40.0, 25.0, 12.0);
        let inverse = (c.proj(1.6) * c.view()).inverse();
        let near = inverse.project_point3(Vec2::ZERO.extend(0.0));
        let far = inverse.project_point3(Vec2::ZERO.extend(0.5));
        let dir = (far - near).normalize();
        let to_target = (c.target - near).normalize();
        assert!(dir.dot(to_target) > 0.9999, "{dir} {to_target}");
    }
}
