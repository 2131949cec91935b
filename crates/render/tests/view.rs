//! The interactive view draws the skinned mesh where its parameters say, and its
//! overlays tint what they should: fold-overs red, the heat map away from the picture.
//! Needs a wgpu adapter: `scripts/setup.sh` installs Mesa's lavapipe.

use glam::Vec2;
use image::{Rgba, RgbaImage};
use render::{Affine, GpuContext, MeshView, Overlay, SkinnedMesh, ViewParams};

const IDENTITY: Affine = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
/// Mirrors x about the middle of an 8-pixel image: every triangle flips.
const MIRROR: Affine = [-1.0, 0.0, 0.0, 1.0, 8.0, 0.0];

struct Scene {
    gpu: GpuContext,
    view: MeshView,
}

impl Scene {
    /// An 8×8 green picture on a two-triangle quad, every vertex bound to node 0.
    fn new(pose: Affine) -> Self {
        let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh)");
        let mut view = MeshView::new(
            gpu.device(),
            gpu.queue(),
            wgpu::TextureFormat::Rgba8Unorm,
            1,
        );
        let picture = RgbaImage::from_pixel(8, 8, Rgba([0, 200, 0, 255]));
        view.set_texture(gpu.device(), gpu.queue(), &picture);
        let rest = [
            Vec2::new(0.0, 0.0),
            Vec2::new(8.0, 0.0),
            Vec2::new(8.0, 8.0),
            Vec2::new(0.0, 8.0),
        ];
        // One triangle of each winding: the view must orient them itself.
        let triangles = [[0, 1, 2], [0, 3, 2]];
        let mesh = SkinnedMesh {
            rest: &rest,
            rows: &[0, 1, 2, 3, 4],
            nodes: &[0, 0, 0, 0],
            weights: &[1.0; 4],
            triangles: &triangles,
        };
        view.set_mesh(gpu.device(), &mesh, &[pose], [8, 8])
            .expect("a valid mesh");
        Self { gpu, view }
    }

    /// Draws the 8×8 image onto a 16×16 target filling it.
    fn draw(&self, overlay: Overlay, show_folds: bool) -> RgbaImage {
        let params = ViewParams {
            scale: [2.0 / 8.0, -2.0 / 8.0],
            offset: [-1.0, 1.0],
            overlay,
            show_folds,
            wireframe: false,
        };
        self.view.prepare(self.gpu.queue(), &params);
        self.gpu
            .offscreen(16, 16, |pass| self.view.paint(pass, false))
            .expect("offscreen drawing")
    }
}

fn count(image: &RgbaImage, pred: impl Fn(&Rgba<u8>) -> bool) -> usize {
    image.pixels().filter(|p| pred(p)).count()
}

fn green(p: &Rgba<u8>) -> bool {
    p[0] < 10 && p[1] > 190 && p[2] < 10 && p[3] == 255
}

fn red(p: &Rgba<u8>) -> bool {
    p[0] > 150 && p[1] < 100 && p[3] == 255
}

#[test]
fn identity_pose_shows_the_picture_without_folds() {
    let scene = Scene::new(IDENTITY);
    let image = scene.draw(Overlay::None, true);
    assert_eq!(count(&image, green), 256, "every pixel is the picture");
}

#[test]
fn a_mirrored_mesh_is_all_fold_over() {
    let scene = Scene::new(MIRROR);
    assert_eq!(count(&scene.draw(Overlay::None, false), green), 256);
    assert_eq!(count(&scene.draw(Overlay::None, true), red), 256);
}

#[test]
fn positions_that_fold_the_mesh_show_the_fold_over_too() {
    // What ARAP and MLS upload: positions, here the quad mirrored left to right.
    let scene = Scene::new(IDENTITY);
    let mirrored = [
        Vec2::new(8.0, 0.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(0.0, 8.0),
        Vec2::new(8.0, 8.0),
    ];
    scene
        .view
        .set_positions(scene.gpu.queue(), &mirrored)
        .expect("positions");
    assert_eq!(count(&scene.draw(Overlay::None, false), green), 256);
    assert_eq!(count(&scene.draw(Overlay::None, true), red), 256);
}

#[test]
fn a_new_pose_moves_the_mesh() {
    let scene = Scene::new(IDENTITY);
    // Half the image width to the right: the left half of the target stays empty.
    let shifted = [1.0, 0.0, 0.0, 1.0, 4.0, 0.0];
    scene
        .view
        .set_pose(scene.gpu.queue(), &[shifted])
        .expect("pose");
    let image = scene.draw(Overlay::None, true);
    for (x, _, p) in image.enumerate_pixels() {
        if x < 8 {
            assert_eq!(p[3], 0, "left half is empty");
        } else {
            assert!(green(p), "right half is the picture");
        }
    }
    assert!(scene.view.set_pose(scene.gpu.queue(), &[]).is_err());
}

#[test]
fn uploaded_positions_replace_the_skinning_until_the_next_pose() {
    let scene = Scene::new(IDENTITY);
    let queue = scene.gpu.queue();
    // The quad squeezed into the right half by positions (8 bytes a vertex).
    let right = [
        Vec2::new(4.0, 0.0),
        Vec2::new(8.0, 0.0),
        Vec2::new(8.0, 8.0),
        Vec2::new(4.0, 8.0),
    ];
    scene.view.set_positions(queue, &right).expect("positions");
    let image = scene.draw(Overlay::None, true);
    for (x, _, p) in image.enumerate_pixels() {
        if x < 8 {
            assert_eq!(p[3], 0, "left half is empty");
        } else {
            assert!(green(p), "right half is the picture: {p:?}");
        }
    }
    // A pose by transforms takes over again.
    scene.view.set_pose(queue, &[IDENTITY]).expect("pose");
    assert_eq!(count(&scene.draw(Overlay::None, true), green), 256);
    // Wrong counts and NaN are refused.
    assert!(scene.view.set_positions(queue, &right[..3]).is_err());
    let mut bad = right;
    bad[2].x = f32::NAN;
    assert!(scene.view.set_positions(queue, &bad).is_err());
}

#[test]
fn vertices_no_node_reaches_stay_at_rest() {
    // A rig without handles: every row is empty, and the picture must stay put.
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh)");
    let mut view = MeshView::new(
        gpu.device(),
        gpu.queue(),
        wgpu::TextureFormat::Rgba8Unorm,
        1,
    );
    view.set_texture(
        gpu.device(),
        gpu.queue(),
        &RgbaImage::from_pixel(8, 8, Rgba([0, 200, 0, 255])),
    );
    let rest = [
        Vec2::new(0.0, 0.0),
        Vec2::new(8.0, 0.0),
        Vec2::new(8.0, 8.0),
        Vec2::new(0.0, 8.0),
    ];
    let mesh = SkinnedMesh {
        rest: &rest,
        rows: &[0; 5],
        nodes: &[],
        weights: &[],
        triangles: &[[0, 1, 2], [0, 2, 3]],
    };
    view.set_mesh(gpu.device(), &mesh, &[], [8, 8])
        .expect("a valid mesh");
    let params = ViewParams {
        scale: [2.0 / 8.0, -2.0 / 8.0],
        offset: [-1.0, 1.0],
        overlay: Overlay::None,
        show_folds: true,
        wireframe: false,
    };
    view.prepare(gpu.queue(), &params);
    let image = gpu
        .offscreen(16, 16, |pass| view.paint(pass, false))
        .expect("offscreen drawing");
    assert_eq!(count(&image, green), 256);
}

#[test]
fn heat_overlay_tints_by_value() {
    let scene = Scene::new(IDENTITY);
    scene
        .view
        .set_heat(scene.gpu.queue(), &[0.0; 4])
        .expect("heat");
    let cold = scene.draw(Overlay::Heat, false);
    scene
        .view
        .set_heat(scene.gpu.queue(), &[1.0; 4])
        .expect("heat");
    let hot = scene.draw(Overlay::Heat, false);
    let mean =
        |image: &RgbaImage, c: usize| image.pixels().map(|p| f64::from(p[c])).sum::<f64>() / 256.0;
    assert!(
        mean(&cold, 2) > mean(&cold, 0),
        "zero weight is blue: {:?}",
        cold.get_pixel(8, 8)
    );
    assert!(
        mean(&hot, 0) > 150.0,
        "full weight is yellow: {:?}",
        hot.get_pixel(8, 8)
    );
    assert_eq!(count(&scene.draw(Overlay::None, false), green), 256);
    assert!(scene.view.set_heat(scene.gpu.queue(), &[0.0; 3]).is_err());
}
