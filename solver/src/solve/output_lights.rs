//! The solution's record of the lights (issue 41, format x.1): the exposure
//! key, the lights as JSON, and the environment baked from the sky and the
//! sun, so that viewers draw the sky behind the geometry and expose the
//! scene from its own radiance.

use super::Solver;
use crate::light::lamp::{Beam, Lamp};
use crate::light::sky::{BelowHorizon, Sky, SkyModel};
use crate::light::sun::Sun;
use crate::light::Lights;
use glam::DVec3;
use serde_json::{json, Value};
use solution::camera::UpAxis;
use solution::format::{
    Environment, Lighting, Representation, Solution, SunDisc, DEFAULT_ENVIRONMENT_SIZE,
};
use solution::raster::tonemap::log_average_luminance;

impl Solver {
    /// The lighting record of `solution` (built from this solver), or `None`
    /// for a scene without lights, whose file stays x.0.
    pub(super) fn lighting(&self, solution: &Solution) -> Option<Lighting> {
        lighting_record(self.lights(), self.lights.power, solution)
    }
}

/// The lighting record of `solution` for `lights` (in the solution's frame),
/// `power` the power they put into the scene (checkpointed by the solve).
pub fn lighting_record(lights: &Lights, power: f64, solution: &Solution) -> Option<Lighting> {
    if lights.is_empty() {
        return None;
    }
    let up = solution.header.up_axis;
    Some(Lighting {
        exposure_key: exposure_key(solution),
        lights_json: Some(lights_json(lights, power).to_string()),
        environment: environment(lights, up, DEFAULT_ENVIRONMENT_SIZE),
    })
}

/// The area-weighted log-average radiance of the solution's vertices
/// (Reinhard et al. 2002, "Photographic tone reproduction for digital
/// images", eq. 1; [`log_average_luminance`]): each vertex weighs a third of
/// the area of each triangle it belongs to, so that a finely meshed shadow
/// edge does not outweigh a large lit floor. A vertex's radiance is its mean
/// over directions (c₀₀/√(4π) for SH, the mean cell for a cube) plus, when
/// textured, factor ⊙ E/π times the texture's mean, as the viewer shows it
/// on average.
pub fn exposure_key(solution: &Solution) -> f32 {
    let y00 = 1.0 / (4.0 * std::f32::consts::PI).sqrt();
    let texture_means: Vec<[f32; 3]> = solution.textures.iter().map(texture_mean).collect();
    let mut samples = Vec::new();
    for batch in &solution.batches {
        let n = batch.representation.coefficients_per_channel() as usize;
        let mut weights = vec![0.0f64; batch.vertices.len()];
        for t in batch.indices.chunks_exact(3) {
            let p = |k: usize| DVec3::from(batch.vertices[t[k] as usize].position.map(f64::from));
            let area = 0.5 * (p(1) - p(0)).cross(p(2) - p(0)).length();
            for &v in t {
                weights[v as usize] += area / 3.0;
            }
        }
        for (v, &w) in weights.iter().enumerate() {
            let c = &batch.coefficients[v * n * 3..(v + 1) * n * 3];
            let mut rgb: [f32; 3] = match batch.representation {
                Representation::Sh { .. } => std::array::from_fn(|ch| c[ch] * y00),
                Representation::Cube { .. } => std::array::from_fn(|ch| {
                    c.iter().skip(ch).step_by(3).sum::<f32>() / n.max(1) as f32
                }),
            };
            if let Some(t) = &batch.texturing {
                let mean = texture_means.get(t.texture as usize).copied();
                let e = t.vertices[v].irradiance_over_pi;
                for ch in 0..3 {
                    rgb[ch] += t.factor[ch] * e[ch] * mean.map_or(1.0, |m| m[ch]);
                }
            }
            samples.push((rgb, w));
        }
    }
    log_average_luminance(samples)
}

/// The mean linear RGB of a texture's texels.
fn texture_mean(texture: &solution::format::Texture) -> [f32; 3] {
    let count = (texture.rgba.len() / 4).max(1) as f64;
    let mut sum = [0.0f64; 3];
    for px in texture.rgba.chunks_exact(4) {
        for ch in 0..3 {
            sum[ch] += f64::from(solution::raster::tonemap::srgb_to_linear(
                f32::from(px[ch]) / 255.0,
            ));
        }
    }
    sum.map(|s| (s / count) as f32)
}

/// The environment seen from the scene: the sky evaluated at each texel's
/// centre ([`Sky::radiance`], which applies the below-horizon rule), and the
/// sun's disc. `None` without a sun and a sky (lamps alone light a closed
/// room, and nothing is seen behind it).
pub fn environment(
    lights: &Lights,
    up: UpAxis,
    (width, height): (u32, u32),
) -> Option<Environment> {
    if lights.sun.is_none() && lights.sky.is_none() {
        return None;
    }
    let mut env = Environment {
        width: 1,
        height: 1,
        texels: vec![[0.0; 3]],
        sun: lights.sun.as_ref().map(sun_disc),
    };
    if let Some(sky) = &lights.sky {
        env.width = width;
        env.height = height;
        env.texels = Vec::with_capacity((width * height) as usize);
        for j in 0..height {
            for i in 0..width {
                let d = DVec3::from(env.texel_direction(up, i, j));
                env.texels.push(sky.radiance(d).as_vec3().to_array());
            }
        }
    }
    Some(env)
}

fn sun_disc(sun: &Sun) -> SunDisc {
    SunDisc {
        direction: sun.direction().normalize().as_vec3().to_array(),
        angular_diameter_deg: sun.angular_diameter_deg() as f32,
        radiance: sun.disc_radiance().as_vec3().to_array(),
    }
}

/// The lights as a JSON record: per light its kind, where it is, its
/// strength in the solver's units, and (lamps) its power.
pub fn lights_json(lights: &Lights, power: f64) -> Value {
    let mut list = Vec::new();
    if let Some(sun) = &lights.sun {
        list.push(json!({
            "kind": "sun",
            "direction": sun.direction().to_array(),
            "irradiance_w_m2": sun.irradiance().to_array(),
            "angular_diameter_deg": sun.angular_diameter_deg(),
            "disc_radiance": sun.disc_radiance().to_array(),
        }));
    }
    if let Some(sky) = &lights.sky {
        list.push(sky_json(sky));
    }
    list.extend(lights.lamps.iter().map(lamp_json));
    json!({
        "lights": list,
        "power_into_scene": power,
    })
}

fn sky_json(sky: &Sky) -> Value {
    let mut v = match sky.model() {
        SkyModel::Uniform { radiance } => {
            json!({"model": "uniform", "radiance": radiance.to_array()})
        }
        SkyModel::CieOvercast { zenith_radiance } => {
            json!({"model": "cie-overcast", "zenith_radiance": zenith_radiance.to_array()})
        }
        SkyModel::Clear {
            turbidity,
            sun_direction,
        } => {
            json!({"model": "clear", "turbidity": turbidity, "sun_direction": sun_direction.to_array()})
        }
        SkyModel::Map { map, north } => {
            let (width, height) = map.size();
            json!({"model": "map", "width": width, "height": height, "north": north.to_array()})
        }
    };
    v["kind"] = json!("sky");
    v["up"] = json!(sky.up().to_array());
    v["horizontal_irradiance_w_m2"] = json!(sky.horizontal_irradiance().to_array());
    v["below_horizon"] = match sky.below_horizon() {
        BelowHorizon::Black => json!("black"),
        BelowHorizon::Same => json!("same"),
        BelowHorizon::Ground { albedo } => json!({"ground_albedo": albedo.to_array()}),
    };
    v
}

fn lamp_json(lamp: &Lamp) -> Value {
    let mut v = json!({
        "kind": "point",
        "name": lamp.name,
        "position": lamp.position.to_array(),
        "intensity_w_sr": lamp.intensity.to_array(),
        "radius": lamp.radius,
        "power_w": lamp.power().to_array(),
        "ies": lamp.profile.as_ref().map(|p| format!("{:?}", p.ies.form)),
    });
    if let Beam::Spot {
        axis,
        cos_inner,
        cos_outer,
    } = lamp.beam
    {
        v["kind"] = json!("spot");
        v["direction"] = json!(axis.to_array());
        v["inner_cone_deg"] = json!(cos_inner.clamp(-1.0, 1.0).acos().to_degrees());
        v["outer_cone_deg"] = json!(cos_outer.clamp(-1.0, 1.0).acos().to_degrees());
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::sky::SkyModel;
    use crate::light::sun::SunPosition;
    use crate::settings::{Preset, SolverSettings};
    use std::f64::consts::PI;

    const RHO: f64 = 0.5;

    /// The open floor of `lights_tests.rs` (a floor of side 2h facing up,
    /// a square of side 0.2h below it facing down, ρ = 0.5) under `lights`,
    /// solved at draft without the ambient term.
    fn solved_floor(half: f64, lights: Lights) -> Solution {
        let scene = crate::solve::lights_tests::open_floor(half, Vec::new(), lights);
        let mut settings = SolverSettings::preset(Preset::Draft);
        settings.ambient = false;
        let mut solver = Solver::new(&scene, &settings).unwrap();
        while solver.step().is_some() {}
        solver.to_solution(false)
    }

    fn uniform_sky(radiance: f64, sun: Option<&Sun>) -> Sky {
        let model = SkyModel::uniform(DVec3::splat(radiance)).unwrap();
        Sky::new(model, DVec3::Y, BelowHorizon::Black, sun).unwrap()
    }

    #[test]
    fn exposure_key_is_the_area_weighted_log_average() {
        // Under a uniform sky of radiance L the open floor shows exactly ρL
        // (`lights_tests.rs`: every cosine-distributed sample carries L) and
        // the square below, which sees the black lower hemisphere, 0. So
        // log L̄ = (A_f ln(ρL + δ) + A_s ln δ) / (A_f + A_s) with the areas
        // 4h² and 0.04h² and δ = 1e-4 × the area-weighted mean luminance.
        // Tolerance 1e-4 relative: f32 radiance and areas, far below any
        // error of the formula (dropping the square's share moves it by 9%).
        let l = 2.0;
        let lights = Lights {
            sky: Some(uniform_sky(l, None)),
            ..Lights::default()
        };
        let solution = solved_floor(2.0, lights);
        let lighting = solution.lighting.as_ref().expect("lights make a record");
        let (af, a_s) = (16.0, 0.16);
        let mean = RHO * l * af / (af + a_s);
        let delta = 1e-4 * mean;
        let expected = ((af * (RHO * l + delta).ln() + a_s * delta.ln()) / (af + a_s)).exp();
        let got = f64::from(lighting.exposure_key);
        assert!((got / expected - 1.0).abs() < 1e-4, "{got} vs {expected}");
        assert_eq!(exposure_key(&solution), lighting.exposure_key);
    }

    #[test]
    fn environment_is_the_sky_at_texel_centres_and_the_sun_disc() {
        let position = SunPosition::from_direction(DVec3::new(0.3, 0.8, 0.5)).unwrap();
        let sun = Sun::new(position, DVec3::splat(100.0), 0.53).unwrap();
        let clear = SkyModel::clear(3.0, sun.direction()).unwrap();
        let sky = Sky::new(clear, DVec3::Y, BelowHorizon::Black, Some(&sun)).unwrap();
        let lights = Lights {
            sun: Some(sun),
            sky: Some(sky.clone()),
            lamps: Vec::new(),
            portals: Vec::new(),
        };
        let env = environment(&lights, UpAxis::PosY, (32, 16)).unwrap();
        assert_eq!((env.width, env.height, env.texels.len()), (32, 16, 512));
        for j in 0..16 {
            for i in 0..32 {
                let d = DVec3::from(env.texel_direction(UpAxis::PosY, i, j));
                let want = sky.radiance(d).as_vec3().to_array();
                assert_eq!(env.texels[(j * 32 + i) as usize], want);
                if j >= 8 {
                    // Below the horizon: black, the sky's default rule.
                    assert_eq!(want, [0.0; 3]);
                } else {
                    assert!(want[2] > 0.0);
                }
            }
        }
        let disc = env.sun.unwrap();
        // E⊥ / Ω, Ω = 4π sin²(d/4): 100 W/m² over 6.72e-5 sr.
        let omega = 4.0 * PI * (0.25 * 0.53f64.to_radians()).sin().powi(2);
        let want = 100.0 / omega;
        assert!((f64::from(disc.radiance[0]) / want - 1.0).abs() < 1e-6);
        let toward = sun.direction().to_array();
        assert!(env.radiance(UpAxis::PosY, toward)[0] > disc.radiance[0]);
        // Lamps alone: no environment (nothing is seen behind a closed room).
        let lamp = Lamp::point("bulb", DVec3::ONE, DVec3::ONE, 0.0).unwrap();
        let lamps = Lights {
            lamps: vec![lamp],
            ..Lights::default()
        };
        assert!(environment(&lamps, UpAxis::PosY, (32, 16)).is_none());
    }

    #[test]
    fn lights_record_names_each_light_and_the_file_is_x_1() {
        let position = SunPosition::from_direction(DVec3::new(0.0, 1.0, 1.0)).unwrap();
        let sun = Sun::new(position, DVec3::splat(50.0), 0.53).unwrap();
        let lamp = Lamp::point("bulb", DVec3::new(0.0, 1.0, 0.0), DVec3::splat(2.0), 0.0)
            .unwrap()
            .with_spot(DVec3::NEG_Y, 20.0, 30.0)
            .unwrap();
        let lights = Lights {
            sun: Some(sun),
            sky: Some(uniform_sky(1.0, Some(&sun))),
            lamps: vec![lamp],
            portals: Vec::new(),
        };
        let solution = solved_floor(2.0, lights);
        let lighting = solution.lighting.as_ref().unwrap();
        let v: Value = serde_json::from_str(lighting.lights_json.as_ref().unwrap()).unwrap();
        let kinds: Vec<&str> = v["lights"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["kind"].as_str().unwrap())
            .collect();
        assert_eq!(kinds, ["sun", "sky", "spot"]);
        let spot = &v["lights"][2];
        assert!((spot["outer_cone_deg"].as_f64().unwrap() - 30.0).abs() < 1e-9);
        assert!(spot["power_w"][0].as_f64().unwrap() > 0.0);
        let bytes = solution::format::encode(&solution).unwrap();
        assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 1, "minor 1");
        let back = solution::format::decode(&bytes).unwrap();
        assert_eq!(back.lighting, solution.lighting);
        // `solver info` prints the key, one line per light and the sun.
        let text = solution::format::describe_lighting_text(back.lighting.as_ref());
        assert!(text.contains("exposure_key: "), "{text}");
        assert!(text.contains("lights: 3\n"), "{text}");
        assert!(text.contains("\"kind\":\"spot\""), "{text}");
        assert!(text.contains("environment: 256x128 RGB f32"), "{text}");
        assert!(text.contains("environment.sun.radiance: "), "{text}");
        // Without lights there is no record, and the file stays x.0.
        assert!(lighting_record(&Lights::default(), 0.0, &solution).is_none());
    }
}
