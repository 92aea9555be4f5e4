//! The simulated camera: the turbine rendered from the vehicle's pose, published on the frames
//! service like a capture source, with exact truth in each frame header.

use hubtrack_capture::sink::ShmSink;
use hubtrack_capture::synthetic::frame_truth;
use hubtrack_capture::{FrameInfo, FrameSink};
use hubtrack_render::{Camera, Renderer};
use hubtrack_runtime::ipc::FramePublisher;
use hubtrack_sim::{camera_pose, render_camera, CameraConfig, Multicopter, Scenario};
use hubtrack_types::{FrameSourceKind, PixelFormat};

/// The camera on the vehicle and the service its frames go to.
pub struct SimCamera {
    sink: ShmSink,
    renderer: Renderer,
    camera: Camera,
    config: CameraConfig,
}

impl SimCamera {
    /// A camera as `config` describes it (through `calibration`, the `[camera]` calibration,
    /// when one is given), publishing on `node`'s frames service.
    pub fn new(
        node: &iceoryx2::prelude::Node<hubtrack_runtime::ipc::Ipc>,
        config: &CameraConfig,
        calibration: Option<&Camera>,
    ) -> anyhow::Result<Self> {
        let camera = render_camera(config, calibration);
        Ok(SimCamera {
            sink: ShmSink::new(
                FramePublisher::new(node, camera.frame_bytes())?,
                FrameSourceKind::Sim,
            ),
            renderer: Renderer::new(camera),
            camera,
            config: config.clone(),
        })
    }

    /// The render camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Renders frame `seq` as seen from `vehicle` and publishes it stamped `now_ns`.
    pub fn publish(
        &mut self,
        scenario: &Scenario,
        vehicle: &Multicopter,
        seq: u64,
        now_ns: u64,
    ) -> anyhow::Result<()> {
        let pose = camera_pose(scenario, vehicle, &self.config);
        let mut scene = scenario.scene.clone();
        scene.frame = seq;
        let info = FrameInfo {
            width: self.camera.width,
            height: self.camera.height,
            format: PixelFormat::Bgr8,
            capture_ns: Some(now_ns),
            truth: Default::default(),
        };
        let renderer = &mut self.renderer;
        self.sink.publish(info, &mut |out| {
            let truth = renderer
                .render(&scene, &pose, out)
                .map_err(|e| hubtrack_capture::CaptureError::Render(e.to_string()))?;
            Ok(Some(frame_truth(&truth)))
        })?;
        Ok(())
    }
}
