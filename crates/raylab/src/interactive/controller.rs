//! The camera and light controller: key presses and releases with their times in, poses out.
//!
//! Pure: no window, no clock. The window loop passes each event's time; the controller
//! integrates the motion in closed form between events, so a pose depends only on which keys
//! were held for how long, never on how often it was asked (the frame rate).

use std::time::Duration;

use glam::{DVec3, Vec3};

/// A motion that lasts while its key is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Motion {
    /// The camera moves along its forward axis (the lab's UP key).
    Forward,
    /// The camera moves back along its forward axis (the lab's DOWN key).
    Back,
    /// The camera turns left about the vertical axis, `R(y)` with a decreasing yaw (LEFT).
    TurnLeft,
    /// The camera turns right (RIGHT).
    TurnRight,
    /// The camera rises (−y, as y is down).
    Up,
    /// The camera sinks (+y).
    Down,
    /// The light moves forward, along the camera's horizontal forward direction (W).
    LightForward,
    /// The light moves back (S).
    LightBack,
    /// The light moves to the camera's left (A).
    LightLeft,
    /// The light moves to the camera's right (D).
    LightRight,
    /// The light rises (Q).
    LightUp,
    /// The light sinks (E).
    LightDown,
}

impl Motion {
    /// Every motion.
    pub const ALL: [Motion; 12] = [
        Motion::Forward,
        Motion::Back,
        Motion::TurnLeft,
        Motion::TurnRight,
        Motion::Up,
        Motion::Down,
        Motion::LightForward,
        Motion::LightBack,
        Motion::LightLeft,
        Motion::LightRight,
        Motion::LightUp,
        Motion::LightDown,
    ];
}

/// Where the camera is, where it looks and where the light is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// The camera's position.
    pub position: Vec3,
    /// The camera's yaw in radians (the lab's `R(y)`; positive turns toward +x).
    pub yaw: f32,
    /// The camera's pitch in radians (positive looks up), within ±[`MAX_PITCH`].
    pub pitch: f32,
    /// The point light's position.
    pub light: Vec3,
}

/// How far the camera may look up or down: just short of straight up, where yaw would lose its
/// meaning.
pub const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

/// How fast the camera turns while LEFT or RIGHT is held: 60° per second.
pub const TURN_RATE: f32 = std::f32::consts::FRAC_PI_3;

/// The speed changes by this factor per [`Controller::faster`] or [`Controller::slower`].
pub const SPEED_STEP: f32 = std::f32::consts::SQRT_2;

/// The speed steps [`Controller::faster`] and [`Controller::slower`] may take from the start:
/// a factor of 2¹⁰ either way.
const MAX_SPEED_STEPS: i32 = 20;

/// A [`Pose`] in double precision: integrated over many intervals, it stays independent of
/// how the time was cut into them to well below `f32` rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PoseF64 {
    position: DVec3,
    yaw: f64,
    pitch: f64,
    light: DVec3,
}

impl From<Pose> for PoseF64 {
    fn from(pose: Pose) -> Self {
        PoseF64 {
            position: pose.position.as_dvec3(),
            yaw: pose.yaw as f64,
            pitch: pose.pitch as f64,
            light: pose.light.as_dvec3(),
        }
    }
}

/// Turns held keys, their durations and mouse drags into a [`Pose`].
#[derive(Clone, Debug)]
pub struct Controller {
    home: Pose,
    pose: PoseF64,
    held: [bool; Motion::ALL.len()],
    /// The time up to which the pose is integrated.
    now: Duration,
    base_speed: f32,
    speed_steps: i32,
}

impl Controller {
    /// A controller starting at `home`, moving at `speed` scene units per second (both the
    /// camera and the light). [`reset`](Self::reset) returns to `home`.
    pub fn new(home: Pose, speed: f32) -> Controller {
        let home = Pose { pitch: home.pitch.clamp(-MAX_PITCH, MAX_PITCH), ..home };
        Controller {
            home,
            pose: home.into(),
            held: [false; Motion::ALL.len()],
            now: Duration::ZERO,
            base_speed: speed,
            speed_steps: 0,
        }
    }

    /// The pose, integrated up to the last [`advance`](Self::advance) or event.
    pub fn pose(&self) -> Pose {
        Pose {
            position: self.pose.position.as_vec3(),
            yaw: self.pose.yaw as f32,
            pitch: self.pose.pitch as f32,
            light: self.pose.light.as_vec3(),
        }
    }

    /// Speed of motion, in scene units per second.
    pub fn speed(&self) -> f32 {
        self.base_speed * SPEED_STEP.powi(self.speed_steps)
    }

    /// Moves faster by [`SPEED_STEP`], up to 2¹⁰ times the starting speed.
    pub fn faster(&mut self, at: Duration) {
        self.advance(at);
        self.speed_steps = (self.speed_steps + 1).min(MAX_SPEED_STEPS);
    }

    /// Moves slower by [`SPEED_STEP`], down to 2⁻¹⁰ times the starting speed.
    pub fn slower(&mut self, at: Duration) {
        self.advance(at);
        self.speed_steps = (self.speed_steps - 1).max(-MAX_SPEED_STEPS);
    }

    /// Whether `motion`'s key is held.
    pub fn is_held(&self, motion: Motion) -> bool {
        self.held[motion as usize]
    }

    /// Whether anything moves while time passes (held keys that do not cancel out).
    pub fn is_moving(&self) -> bool {
        let (velocity, turn, light) = self.velocities();
        velocity != DVec3::ZERO || turn != 0.0 || light != DVec3::ZERO
    }

    /// `motion`'s key went down at time `at`. Times are measured from any fixed instant; an
    /// event earlier than one already seen counts as happening at that one.
    pub fn press(&mut self, motion: Motion, at: Duration) {
        self.advance(at);
        self.held[motion as usize] = true;
    }

    /// `motion`'s key came up at time `at`.
    pub fn release(&mut self, motion: Motion, at: Duration) {
        self.advance(at);
        self.held[motion as usize] = false;
    }

    /// Releases every key at time `at` (the window lost the keyboard).
    pub fn release_all(&mut self, at: Duration) {
        self.advance(at);
        self.held = [false; Motion::ALL.len()];
    }

    /// Turns the camera by a mouse drag of `(dx, dy)` pixels at time `at` with a focal length
    /// of `focal_px` pixels, grabbing the picture: what was under the cursor at the centre of
    /// the image stays under it. Dragging right turns left; dragging down looks up.
    pub fn drag(&mut self, dx: f32, dy: f32, focal_px: f32, at: Duration) {
        self.advance(at);
        if !(dx.is_finite() && dy.is_finite() && focal_px.is_finite() && focal_px > 0.0) {
            return;
        }
        let max_pitch = MAX_PITCH as f64;
        self.pose.yaw = wrap_angle(self.pose.yaw - (dx as f64 / focal_px as f64).atan());
        self.pose.pitch =
            (self.pose.pitch + (dy as f64 / focal_px as f64).atan()).clamp(-max_pitch, max_pitch);
    }

    /// Back to the starting pose (keys stay as they are, and so does the speed).
    pub fn reset(&mut self, at: Duration) {
        self.advance(at);
        self.pose = self.home.into();
    }

    /// Integrates the motion of the held keys up to time `to`.
    ///
    /// In closed form: over an interval the yaw changes at a constant rate ω, and the camera
    /// moves along a forward direction that turns with it, `∫ v·f(θ₀ + ωt) dt`, which is an arc
    /// of a circle. So holding UP and RIGHT for a second gives the same pose whether it is asked
    /// for once or at every frame of 60 or 144 per second.
    pub fn advance(&mut self, to: Duration) {
        if to <= self.now {
            return;
        }
        let t = (to - self.now).as_secs_f64();
        self.now = to;
        let (velocity, turn, light) = self.velocities();
        if velocity == DVec3::ZERO && turn == 0.0 && light == DVec3::ZERO {
            return;
        }
        // ∫₀ᵗ sin(θ₀ + ωs) ds = t·sin(θm)·sinc(ωt/2) with θm the middle yaw, and the same with
        // cos: stable for any ω, including 0.
        let yaw0 = self.pose.yaw;
        let half = turn * t / 2.0;
        let sinc = if half.abs() < 1e-4 { 1.0 - half * half / 6.0 } else { half.sin() / half };
        let (sin_mid, cos_mid) = (yaw0 + half).sin_cos();
        let (int_sin, int_cos) = (t * sin_mid * sinc, t * cos_mid * sinc);
        let (sin_pitch, cos_pitch) = self.pose.pitch.sin_cos();
        // The camera: forward f = (sin θ cos p, −sin p, cos θ cos p), right r = (cos θ, 0, −sin θ)
        // and up (0, −1, 0); velocity is (forward, right, up) speeds.
        let camera = DVec3::new(
            velocity.x * cos_pitch * int_sin + velocity.y * int_cos,
            -velocity.x * sin_pitch * t - velocity.z * t,
            velocity.x * cos_pitch * int_cos - velocity.y * int_sin,
        );
        // The light moves in the camera's horizontal frame, so forward means away from the
        // camera whatever its pitch.
        let light = DVec3::new(
            light.x * int_sin + light.y * int_cos,
            -light.z * t,
            light.x * int_cos - light.y * int_sin,
        );
        self.pose.position += camera;
        self.pose.light += light;
        self.pose.yaw = wrap_angle(yaw0 + turn * t);
    }

    /// The camera's (forward, right, up) speeds, its turn rate in radians per second, and the
    /// light's (forward, right, up) speeds, from the held keys.
    fn velocities(&self) -> (DVec3, f64, DVec3) {
        let axis = |plus: Motion, minus: Motion| {
            self.is_held(plus) as i32 as f64 - self.is_held(minus) as i32 as f64
        };
        let speed = self.speed() as f64;
        let camera =
            DVec3::new(axis(Motion::Forward, Motion::Back), 0.0, axis(Motion::Up, Motion::Down))
                * speed;
        let turn = axis(Motion::TurnRight, Motion::TurnLeft) * TURN_RATE as f64;
        let light = DVec3::new(
            axis(Motion::LightForward, Motion::LightBack),
            axis(Motion::LightRight, Motion::LightLeft),
            axis(Motion::LightUp, Motion::LightDown),
        ) * speed;
        (camera, turn, light)
    }
}

/// An angle in radians brought into `(−π, π]`, so that hours of turning keep full precision.
fn wrap_angle(angle: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if (-PI..=PI).contains(&angle) {
        return angle;
    }
    let wrapped = angle - TAU * (angle / TAU).round();
    if wrapped <= -PI { wrapped + TAU } else { wrapped }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, PI};

    use super::*;

    fn home() -> Pose {
        Pose {
            position: Vec3::new(0.0, 0.0, -3.0),
            yaw: 0.0,
            pitch: 0.0,
            light: Vec3::new(0.0, -0.5, -0.7),
        }
    }

    fn secs(s: f64) -> Duration {
        Duration::from_secs_f64(s)
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    /// Holds `motions` from `from` to `to` seconds, asking for the pose `steps` times between.
    fn hold(controller: &mut Controller, motions: &[Motion], from: f64, to: f64, steps: u32) {
        for &m in motions {
            controller.press(m, secs(from));
        }
        for i in 1..=steps {
            controller.advance(secs(from + (to - from) * i as f64 / steps as f64));
        }
        for &m in motions {
            controller.release(m, secs(to));
        }
    }

    #[test]
    fn up_moves_forward_at_the_speed_for_exactly_as_long_as_it_is_held() {
        let mut c = Controller::new(home(), 2.0);
        hold(&mut c, &[Motion::Forward], 1.0, 1.25, 1);
        c.advance(secs(10.0)); // released: no more motion
        assert!(close(c.pose().position, Vec3::new(0.0, 0.0, -2.5)), "{:?}", c.pose());
        hold(&mut c, &[Motion::Back], 10.0, 10.5, 7);
        assert!(close(c.pose().position, Vec3::new(0.0, 0.0, -3.5)), "{:?}", c.pose());
        assert_eq!(c.pose().yaw, 0.0);
        assert_eq!(c.pose().light, home().light);
    }

    #[test]
    fn left_and_right_turn_at_sixty_degrees_per_second() {
        let mut c = Controller::new(home(), 1.0);
        hold(&mut c, &[Motion::TurnRight], 0.0, 1.5, 3);
        assert!((c.pose().yaw - FRAC_PI_2).abs() < 1e-6, "{}", c.pose().yaw);
        hold(&mut c, &[Motion::TurnLeft], 2.0, 2.75, 1);
        assert!((c.pose().yaw - PI / 4.0).abs() < 1e-6);
        assert_eq!(c.pose().position, home().position);
        // Turned right by 90°, forward is +x.
        let mut c = Controller::new(Pose { yaw: FRAC_PI_2, ..home() }, 1.0);
        hold(&mut c, &[Motion::Forward], 0.0, 1.0, 1);
        assert!(close(c.pose().position, Vec3::new(1.0, 0.0, -3.0)), "{:?}", c.pose());
    }

    #[test]
    fn moving_while_turning_follows_an_arc_whatever_the_frame_rate() {
        // Forward at v while turning at ω traces a circle of radius v/ω: after half a turn
        // (3 s at 60°/s) the camera is 2v/ω to the right of where it started, facing back.
        let v = 1.0f32;
        let radius = v / TURN_RATE;
        let mut poses = Vec::new();
        for steps in [1, 3, 60, 144 * 3] {
            let mut c = Controller::new(home(), v);
            hold(&mut c, &[Motion::Forward, Motion::TurnRight], 0.0, 3.0, steps);
            poses.push(c.pose());
        }
        let expected = home().position + Vec3::new(2.0 * radius, 0.0, 0.0);
        for pose in &poses {
            assert!(close(pose.position, expected), "{pose:?} vs {expected}");
            assert!((pose.yaw.abs() - PI).abs() < 1e-5, "{}", pose.yaw);
            assert!(close(pose.position, poses[0].position));
        }
        // A numerical integral with small steps agrees.
        let (mut p, mut yaw, dt) = (home().position, 0.0f64, 1e-5f64);
        for _ in 0..(3.0 / dt) as usize {
            let mid = yaw + TURN_RATE as f64 * dt / 2.0;
            p += Vec3::new(mid.sin() as f32, 0.0, mid.cos() as f32) * (v * dt as f32);
            yaw += TURN_RATE as f64 * dt;
        }
        assert!((p - expected).length() < 1e-3, "{p}");
    }

    #[test]
    fn vertical_keys_and_pitch() {
        let mut c = Controller::new(home(), 1.0);
        hold(&mut c, &[Motion::Up], 0.0, 0.5, 2);
        assert!(close(c.pose().position, Vec3::new(0.0, -0.5, -3.0)));
        hold(&mut c, &[Motion::Down], 1.0, 2.0, 2);
        assert!(close(c.pose().position, Vec3::new(0.0, 0.5, -3.0)));
        // Looking up 90° (clamped to 89°) and moving forward rises almost straight up.
        c.drag(0.0, 1e9, 500.0, secs(2.0));
        assert_eq!(c.pose().pitch, MAX_PITCH);
        hold(&mut c, &[Motion::Forward], 3.0, 4.0, 1);
        let moved = c.pose().position - Vec3::new(0.0, 0.5, -3.0);
        let expected = Vec3::new(0.0, -MAX_PITCH.sin(), MAX_PITCH.cos());
        assert!(close(moved, expected), "{moved}");
    }

    #[test]
    fn the_light_moves_in_the_cameras_horizontal_frame() {
        let mut c = Controller::new(home(), 1.0);
        let light = home().light;
        hold(&mut c, &[Motion::LightForward], 0.0, 1.0, 1);
        hold(&mut c, &[Motion::LightRight], 1.0, 3.0, 4);
        hold(&mut c, &[Motion::LightUp], 3.0, 3.5, 1);
        assert!(close(c.pose().light, light + Vec3::new(2.0, -0.5, 1.0)), "{:?}", c.pose());
        hold(&mut c, &[Motion::LightBack, Motion::LightLeft, Motion::LightDown], 4.0, 4.5, 3);
        assert!(close(c.pose().light, light + Vec3::new(1.5, 0.0, 0.5)), "{:?}", c.pose());
        // Turned right by 90°, forward is +x and right is −z; looking down does not change that.
        let mut c = Controller::new(Pose { yaw: FRAC_PI_2, pitch: -0.5, ..home() }, 1.0);
        hold(&mut c, &[Motion::LightForward, Motion::LightRight], 0.0, 1.0, 1);
        assert!(close(c.pose().light, light + Vec3::new(1.0, 0.0, -1.0)), "{:?}", c.pose());
        assert_eq!(c.pose().position, home().position);
    }

    #[test]
    fn opposite_keys_cancel_and_late_events_do_not_rewind() {
        let mut c = Controller::new(home(), 1.0);
        c.press(Motion::Forward, secs(1.0));
        c.press(Motion::Back, secs(1.0));
        assert!(!c.is_moving());
        c.advance(secs(2.0));
        assert_eq!(c.pose(), home());
        c.release(Motion::Back, secs(2.0));
        assert!(c.is_moving() && c.is_held(Motion::Forward));
        c.advance(secs(3.0));
        // An event stamped before the last one counts as happening now: no motion backwards.
        c.release(Motion::Forward, secs(2.5));
        c.advance(secs(9.0));
        assert!(close(c.pose().position, Vec3::new(0.0, 0.0, -2.0)), "{:?}", c.pose());
    }

    #[test]
    fn speed_steps_reset_and_release_all() {
        let mut c = Controller::new(home(), 1.0);
        c.faster(secs(0.0));
        c.faster(secs(0.0));
        assert!((c.speed() - 2.0).abs() < 1e-6);
        for _ in 0..100 {
            c.faster(secs(0.0));
        }
        assert!((c.speed() - 1024.0).abs() < 1e-2);
        for _ in 0..100 {
            c.slower(secs(0.0));
        }
        assert!((c.speed() - 1.0 / 1024.0).abs() < 1e-6);
        let mut c = Controller::new(home(), 1.0);
        c.slower(secs(0.0));
        c.slower(secs(0.0));
        hold(&mut c, &[Motion::Forward, Motion::LightUp], 0.0, 1.0, 1);
        assert!(close(c.pose().position, Vec3::new(0.0, 0.0, -2.5)));
        c.drag(100.0, 0.0, 500.0, secs(1.0));
        c.reset(secs(1.0));
        assert_eq!(c.pose(), home());
        c.press(Motion::TurnLeft, secs(1.0));
        c.release_all(secs(2.0));
        c.advance(secs(5.0));
        assert!((c.pose().yaw + PI / 3.0).abs() < 1e-6);
        assert!(!c.is_moving());
    }

    #[test]
    fn dragging_grabs_the_picture() {
        let mut c = Controller::new(home(), 1.0);
        // A point 100 px right of the centre at f = 500 is atan(0.2) to the right; dragging it
        // to the centre turns the camera right by that angle.
        c.drag(-100.0, 0.0, 500.0, secs(0.0));
        assert!((c.pose().yaw - 0.2f32.atan()).abs() < 1e-7);
        c.drag(0.0, 50.0, 500.0, secs(0.0));
        assert!((c.pose().pitch - 0.1f32.atan()).abs() < 1e-7);
        let before = c.pose();
        c.drag(f32::NAN, 1.0, 500.0, secs(0.0));
        c.drag(1.0, 1.0, 0.0, secs(0.0));
        assert_eq!(c.pose(), before);
    }

    #[test]
    fn a_drag_while_moving_turns_at_its_time() {
        // Forward for a second, with a drag to the right by 90° half-way: half a unit along z,
        // then half a unit along x, however often the pose was asked for before the drag.
        let focal = 500.0;
        // atan(1e7) is 90° to within 1e-7.
        let dx = -focal * 1e7;
        for steps in [1, 10] {
            let mut c = Controller::new(home(), 1.0);
            c.press(Motion::Forward, secs(0.0));
            for i in 1..steps {
                c.advance(secs(0.5 * i as f64 / steps as f64));
            }
            c.drag(dx, 0.0, focal, secs(0.5));
            c.release(Motion::Forward, secs(1.0));
            assert!((c.pose().yaw - FRAC_PI_2).abs() < 1e-4, "{}", c.pose().yaw);
            let expected = home().position + Vec3::new(0.5, 0.0, 0.5);
            assert!((c.pose().position - expected).length() < 1e-4, "{:?}", c.pose());
        }
    }

    #[test]
    fn hours_of_turning_keep_the_yaw_in_range() {
        let mut c = Controller::new(home(), 1.0);
        hold(&mut c, &[Motion::TurnRight], 0.0, 3600.0 * 5.0 + 0.75, 1000);
        // 60°/s for 5 h and 0.75 s: a whole number of turns plus 45°.
        assert!((c.pose().yaw - PI / 4.0).abs() < 1e-3, "{}", c.pose().yaw);
        {
            use std::f64::consts::{FRAC_PI_2, PI};
            assert!((wrap_angle(3.0 * PI / 2.0) + FRAC_PI_2).abs() < 1e-12);
            assert_eq!(wrap_angle(PI), PI);
            assert!(wrap_angle(-PI - 1e-3) > 0.0);
        }
    }
}
