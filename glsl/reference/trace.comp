#version 460
// Ground truth: a progressive light (particle) tracer (GUIDE §3). Each
// invocation emits one photon, follows it through specular chains (exact
// Fresnel, Snell, total internal reflection, Beer-Lambert absorption inside
// dielectrics) and through the medium (free-flight sampling against a
// majorant with null collisions, Henyey-Greenstein scattering), and at every
// diffuse hit and every medium collision connects it to the camera, but for
// photons straight from a point, spot, directional, rect or triangle light:
// their direct light (L D E, L V E) is camera.comp's, by shadow rays.
//
// Measurement (the pinhole camera's importance): a photon of flux Phi at x
// adds to pixel j's mean radiance
//     dL_j = Phi f cos(theta_x) T(x, eye) / (d^2 cos^3(theta_c) A_pix)
// where f is the BRDF (albedo/pi) or sigma_s p(omega) per unit length for a
// medium event, d = |x - eye|, theta_c the angle to the optical axis and
// A_pix the pixel's area on the image plane at unit distance; that is the
// change of variables from image-plane area to surface area (or volume).
#include "common.glsl"
#include "aim_guide.glsl"

layout(local_size_x = 64) in;

// This invocation's photon for the aim guide: the light and cell it was
// aimed by (guide_light = GUIDE_UNAIMED: not aimed by a guide), g there,
// and whether it reached the image.
const uint GUIDE_UNAIMED = 0xffffffffu;
uint guide_light = GUIDE_UNAIMED;
uint guide_photon_cell = 0u;
float guide_photon_density = 1.0;
bool photon_useful = false;

// The point of the unit square an aimed photon of light l maps onto the
// aimed region: drawn by the light's guide (and noted for its count), or u.
vec2 aimed_square_point(uint l, bool guided, vec2 u) {
    if (!guided) return u;
    guide_light = l;
    return guide_sample(l, u, guide_photon_cell, guide_photon_density);
}

// Adds a photon's contribution to pixel `pixel` of this pass's image
// `component`, divided by the photons emitted this pass.
void splat(ivec2 pixel, uint component, vec3 value) {
    add_pass(uint(pixel.y) * image_width() + uint(pixel.x), component, value / pc.pass_photons);
}

// Projects x into the image; returns false when it falls outside or behind.
// `to_eye` is the unit direction from x to the eye, `dist` the distance, and
// `measurement` the factor 1 / (d^2 cos^3 theta_c A_pix).
bool camera_connection(vec3 x, out ivec2 pixel, out vec3 to_eye, out float dist, out float measurement) {
    vec4 clip = frame.view_proj * vec4(x, 1.0);
    if (clip.w <= 0.0) return false;
    vec2 ndc = clip.xy / clip.w;
    if (any(lessThan(ndc, vec2(-1.0))) || any(greaterThanEqual(ndc, vec2(1.0)))) return false;
    vec2 p = (ndc * 0.5 + 0.5) * frame.viewport.xy;
    // Rounding can put ndc just below 1 exactly on the far edge: clamp.
    pixel = min(ivec2(floor(p)), ivec2(frame.viewport.xy) - 1);
    vec3 v = frame.eye.xyz - x;
    dist = length(v);
    to_eye = v / dist;
    vec3 forward = -vec3(frame.view[0][2], frame.view[1][2], frame.view[2][2]);
    float cos_c = dot(-to_eye, forward);
    if (cos_c <= 0.0) return false;
    float pixel_side = 2.0 * frame.eye.w / frame.viewport.y;
    measurement = 1.0 / (dist * dist * cos_c * cos_c * cos_c * pixel_side * pixel_side);
    return true;
}

// Path-type tags (Heckbert notation): what happened before this connection.
uint tag_for(uint specular_bounces, bool scattered_or_bounced, bool at_medium) {
    if (scattered_or_bounced) return COMPONENT_OTHER;
    if (at_medium) return specular_bounces == 0u ? COMPONENT_AIRLIGHT : COMPONENT_VOLUME_CAUSTICS;
    return specular_bounces == 0u ? COMPONENT_DIRECT : COMPONENT_SURFACE_CAUSTICS;
}

// Light sources in one list: the point/spot/directional lights (0 ..
// L-1), the area lights (L .. L+A-1), the environment's table (L+A) and its
// sun (L+A+1), each with its luminance power (W).
uint source_count() { return frame.counts.x + frame.components.y + 2u; }
float source_power(uint s) {
    uint l = frame.counts.x, a = frame.components.y;
    if (s < l) return lights[s].power.x;
    if (s < l + a) return emitters[s - l].radiance.w;
    if (!environment_present()) return 0.0;
    return s == l + a ? environment.table.z : environment.sun_radiance.w;
}

// Picks a light source with probability proportional to its power.
uint pick_light(float u, out float probability) {
    uint count = source_count();
    float total = 0.0;
    for (uint l = 0u; l < count; ++l) total += source_power(l);
    if (total <= 0.0) {
        probability = 0.0;
        return 0u;
    }
    float target = u * total;
    float running = 0.0;
    uint last = 0u;
    for (uint l = 0u; l < count; ++l) {
        float p = source_power(l);
        if (p <= 0.0) continue;
        last = l;
        running += p;
        if (target < running) {
            probability = p / total;
            return l;
        }
    }
    probability = source_power(last) / total;
    return last;
}

// Emits a photon from area light `e`: a point uniform over its area (pdf
// 1/A, `sample_emitter_point`) and a cosine-weighted direction about its
// normal there (pdf cos/pi), so every photon carries the power pi L A.
void emit_area(uint e, inout uint rng, out vec3 origin, out vec3 dir, out vec3 flux) {
    Emitter em = emitters[e];
    vec2 u = vec2(rng_next(rng), rng_next(rng));
    vec2 v = vec2(rng_next(rng), rng_next(rng));
    vec3 n;
    float area;
    sample_emitter_point(em, u, origin, n, area);
    origin = offset_origin(origin, n);
    dir = cosine_hemisphere(v, n);
    flux = em.radiance.rgb * PI * area;
}

// Emits a photon from the environment: an incoming direction w (table:
// importance-sampled by luminance, emitters.glsl; sun: uniform over its
// disc) and a point uniform on the disc of the scene's bounding radius R
// perpendicular to w, just outside the scene, travelling along -w:
// flux = L(w) pi R^2 / p(w).
void emit_environment(bool sun, inout uint rng, out vec3 origin, out vec3 dir, out vec3 flux) {
    vec2 u = vec2(rng_next(rng), rng_next(rng));
    vec3 w;
    float pdf;
    vec3 radiance;
    if (sun) {
        float cos_max = environment.sun.w;
        w = uniform_cone(u, environment.sun.xyz, cos_max);
        pdf = 1.0 / (2.0 * PI * (1.0 - cos_max));
        radiance = environment.sun_radiance.rgb;
    } else {
        w = sample_environment_table(u, pdf);
        radiance = environment_table_radiance(w);
    }
    vec3 c = frame.scene_sphere.xyz;
    float r = frame.scene_sphere.w;
    vec3 t, b;
    basis(w, t, b);
    vec2 v = vec2(rng_next(rng), rng_next(rng));
    float rr = r * sqrt(v.x);
    float phi = 2.0 * PI * v.y;
    origin = c + w * (r * 1.01) + t * (rr * cos(phi)) + b * (rr * sin(phi));
    dir = -w;
    flux = pdf > 0.0 ? radiance * (PI * r * r) / pdf : vec3(0.0);
}

// Emits a photon from light l: origin, direction, and flux / pdf (W, per
// channel, before dividing by the number of photons).
//
// Photons are aimed at the specular objects (Jensen's projection maps, as a
// mixture so that nothing is left unsampled): with probability
// q = pc.aim_share a direction toward the bounding sphere of every specular
// triangle (pc.aim: centre, radius), else the light's own distribution; the
// flux divides by the mixture's pdf, so the estimate stays unbiased while
// the caustics (what the visible points behind glass and water gather)
// get a share q of the photons instead of the share of the solid angle
// the specular objects subtend (0.6% for ball_lens). Within the aimed
// region the aim guide (aim_guide.glsl) places them where earlier passes'
// photons reached the image: the aimed pdf is the uniform one times g.
void emit(uint l, inout uint rng, out vec3 origin, out vec3 dir, out vec3 flux) {
    Light light = lights[l];
    uint kind = floatBitsToUint(light.position.w);
    // A random choice per photon. (Stratifying it by invocation, aimed
    // photons first, measured 2x slower on ball_lens at 128^2; not for the
    // float atomics, which cost nothing measurable there: BENCHMARKS.md,
    // "Ground truth: time to quality".)
    float choice = rng_next(rng);
    vec2 u = vec2(rng_next(rng), rng_next(rng));
    vec3 aim_center = pc.aim.xyz;
    float aim_radius = pc.aim.w;
    bool guided = pc.aim_guide != 0u;
    if (kind == LIGHT_POINT || kind == LIGHT_SPOT) {
        origin = light.position.xyz;
        vec3 to_aim = aim_center - origin;
        float d = length(to_aim);
        // The light inside the sphere (or no specular object): no aiming.
        float q = (aim_radius > 0.0 && d > aim_radius) ? pc.aim_share : 0.0;
        vec3 axis = q > 0.0 ? to_aim / d : vec3(0.0, 1.0, 0.0);
        float cos_aim = q > 0.0 ? sqrt(max(0.0, 1.0 - aim_radius * aim_radius / (d * d))) : 1.0;
        float cos_outer = light.direction.w;
        bool aimed = choice < q;
        if (aimed) dir = uniform_cone(aimed_square_point(l, guided, u), axis, cos_aim);
        else if (kind == LIGHT_POINT) dir = uniform_sphere(u);
        else dir = uniform_cone(u, light.direction.xyz, cos_outer);
        float base_pdf = kind == LIGHT_POINT ? 1.0 / (4.0 * PI)
            : (dot(dir, light.direction.xyz) >= cos_outer ? 1.0 / (2.0 * PI * (1.0 - cos_outer)) : 0.0);
        float aim_pdf = 0.0;
        if (q > 0.0 && dot(dir, axis) >= cos_aim) {
            float g = !guided ? 1.0
                : aimed ? guide_photon_density
                : guide_density(l, uniform_cone_coords(dir, axis, cos_aim));
            aim_pdf = g / (2.0 * PI * (1.0 - cos_aim));
        }
        float pdf = (1.0 - q) * base_pdf + q * aim_pdf;
        float falloff = kind == LIGHT_POINT ? 1.0
            : spot_falloff(dot(dir, light.direction.xyz), cos_outer, light.intensity.w);
        flux = pdf > 0.0 ? light.intensity.rgb * falloff / pdf : vec3(0.0);
    } else {
        // A disk of the scene's bounding radius, perpendicular to the light,
        // just outside the scene: every ray that can reach the scene leaves
        // it. Aimed: the disk the specular sphere projects onto it.
        vec3 c = frame.scene_sphere.xyz;
        float r = frame.scene_sphere.w;
        dir = light.direction.xyz;
        vec3 t, b;
        basis(dir, t, b);
        vec2 aim_offset = vec2(dot(aim_center - c, t), dot(aim_center - c, b));
        float q = aim_radius > 0.0 ? pc.aim_share : 0.0;
        bool aimed = choice < q;
        vec2 center = aimed ? aim_offset : vec2(0.0);
        float radius = aimed ? aim_radius : r;
        vec2 v = aimed ? aimed_square_point(l, guided, u) : u;
        float rr = radius * sqrt(v.x);
        float phi = 2.0 * PI * v.y;
        vec2 p = center + vec2(rr * cos(phi), rr * sin(phi));
        origin = c - dir * (r * 1.01) + t * p.x + b * p.y;
        float base_pdf = dot(p, p) <= r * r ? 1.0 / (PI * r * r) : 0.0;
        vec2 from_aim = p - aim_offset;
        float aim_pdf = 0.0;
        if (q > 0.0 && dot(from_aim, from_aim) <= aim_radius * aim_radius) {
            float from_phi = atan(from_aim.y, from_aim.x);
            if (from_phi < 0.0) from_phi += 2.0 * PI;
            vec2 disk_u = vec2(dot(from_aim, from_aim) / (aim_radius * aim_radius), from_phi / (2.0 * PI));
            float g = !guided ? 1.0 : aimed ? guide_photon_density : guide_density(l, disk_u);
            aim_pdf = g / (PI * aim_radius * aim_radius);
        }
        float pdf = (1.0 - q) * base_pdf + q * aim_pdf;
        // Beyond the scene's disk nothing is reached: such a photon is wasted.
        flux = (pdf > 0.0 && base_pdf > 0.0) ? light.intensity.rgb / pdf : vec3(0.0);
    }
}

// The camera connections: `s` is the photon's state where it is (the
// region its segment to the eye lies in when nothing blocks it).
void connect_surface(SpecularState s, vec3 x, vec3 n, vec3 albedo, uint tag, inout uint rng) {
    ivec2 pixel;
    vec3 to_eye;
    float dist, measurement;
    if (!camera_connection(x, pixel, to_eye, dist, measurement)) return;
    float cos_x = dot(n, to_eye);
    if (cos_x <= 0.0) return;
    vec3 o = offset_origin(x, n);
    if (trace_any(o, to_eye, 0.0, dist * (1.0 - 1e-4))) return;
    vec3 tr = region_transmittance(s, o, to_eye, dist, rng);
    photon_useful = true;
    splat(pixel, tag, s.weight * (albedo / PI) * cos_x * measurement * tr);
}

void connect_medium(SpecularState s, vec3 x, vec3 weight_sigma_s, float g, uint tag, inout uint rng) {
    ivec2 pixel;
    vec3 to_eye;
    float dist, measurement;
    if (!camera_connection(x, pixel, to_eye, dist, measurement)) return;
    if (trace_any(x, to_eye, 0.0, dist * (1.0 - 1e-4))) return;
    vec3 tr = region_transmittance(s, x, to_eye, dist, rng);
    photon_useful = true;
    splat(pixel, tag, weight_sigma_s * hg_phase(dot(s.dir, to_eye), g) * measurement * tr);
}

// Progressive photon mapping, surface (Knaus & Zwicker 2011, Eq. 9 with the
// disk kernel): a photon of flux Phi landing at x adds to every visible
// point v within r of it, on the side of the surface v's camera path sees,
//     L_v += W_v (albedo/pi) Phi / (pi r_i^2 N_i)
// (W_v (albedo/pi) is stored in the point, N_i is the photons of pass i).
// Each pass is an independent estimate with its own radius, shrunk after
// pass i by Knaus & Zwicker's Eq. 15, r_{i+1}^2 = r_i^2 (i + alpha)/(i + 1)
// (alpha = 2/3; reference.rs `next_radius`): the mean over passes converges
// to the exact radiance: the bias of pass i goes as r_i^2, and the
// variance of the mean still vanishes since r_i shrinks that slowly.
// Normals more than 60 degrees apart mean another surface (a corner): those
// points are skipped, which changes nothing in the limit r -> 0.
void gather_surface(vec3 x, vec3 arrival_side, vec3 flux, uint tag) {
    float r = pc.radius;
    float side = 2.0 * r;
    ivec3 lo = grid_cell(x - vec3(r), side);
    ivec3 hi = grid_cell(x + vec3(r), side);
    vec3 scale = flux / (PI * r * r * pc.pass_photons);
    for (int cz = lo.z; cz <= hi.z; ++cz)
    for (int cy = lo.y; cy <= hi.y; ++cy)
    for (int cx = lo.x; cx <= hi.x; ++cx) {
        ivec3 c = ivec3(cx, cy, cz);
        uint i = surface_heads[grid_bucket(c, pc.surface_mask)];
        // A chain holds at most every point once; the bound guards the loop.
        for (uint guard = 0u; i != REFERENCE_GRID_NONE && guard < image_pixels() * visible_points_per_pixel(); ++guard) {
            VisiblePoint vp = visible_points[i];
            // Other cells share this bucket: count each point in its own cell only.
            if (grid_cell(vp.position.xyz, side) == c) {
                vec3 d = vp.position.xyz - x;
                if (dot(d, d) < r * r && dot(vp.normal.xyz, arrival_side) > 0.5) {
                    add_pass(i >> pc.fresnel_splits, tag, scale * vp.weight.rgb);
                    photon_useful = true;
                }
            }
            i = surface_next[i];
        }
    }
}

// Stores a medium collision in the volume photon map (volume_gather.comp
// gathers it along camera paths seen through specular chains).
void store_volume_photon(vec3 x, vec3 d, vec3 flux, uint tag) {
    uint index = atomicAdd(volume_photon_count, 1u);
    if (index >= pc.volume_capacity) return; // counted: the host reports the overflow
    photon_useful = true; // whether a gather point finds it is not known here
    VolumePhoton photon;
    photon.position = vec4(x, uintBitsToFloat(tag));
    photon.direction = vec4(d, 0.0);
    photon.flux = vec4(flux / pc.pass_photons, 0.0);
    volume_photons[index] = photon;
    uint bucket = grid_bucket(grid_cell(x, volume_cell_side()), pc.volume_mask);
    volume_next[index] = atomicExchange(volume_heads[bucket], index);
}

// Emits and follows one photon.
void trace_photon() {
    uint rng = rng_seed(gl_GlobalInvocationID.x, pc.seed);
    float light_probability;
    uint l = pick_light(rng_next(rng), light_probability);
    if (light_probability <= 0.0) return; // every light is black
    SpecularState s;
    bool extended = l >= frame.counts.x;
    uint areas_end = frame.counts.x + frame.components.y;
    // camera.comp samples the direct light of the point, spot and
    // directional lights and of rect and triangle area lights by shadow
    // rays; the environment's and sphere lights' photons are connected and
    // gathered from their first hit on.
    bool sampled_by_camera = !extended
        || (l < areas_end && emitter_sampled_by_camera(emitters[l - frame.counts.x]));
    if (!extended) emit(l, rng, s.origin, s.dir, s.weight);
    else if (l < areas_end) emit_area(l - frame.counts.x, rng, s.origin, s.dir, s.weight);
    else emit_environment(l > areas_end, rng, s.origin, s.dir, s.weight);
    s.weight /= light_probability;
    leave_dielectric(s); // lights are outside objects

    uint specular = 0u;
    bool scattered_or_bounced = false;
    uint diffuse_left = pc.diffuse_bounces;
    bool has_medium = medium_present();

    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        // Direct light (L D, L V) is camera.comp's for these photons.
        bool straight_from_sampled_light = sampled_by_camera && specular == 0u && !scattered_or_bounced;
        Hit hit;
        bool found = trace_closest(s.origin, s.dir, 0.0, 1e30, hit);
        float t_hit = found ? hit.t : 1e30;

        // The scene's medium outside dielectrics, or the homogeneous one
        // inside a dielectric that holds one (turbid water: free-flight
        // sampling after the photon entered it through the surface).
        bool inside_medium = scatters_inside(s);
        if ((has_medium && !s.inside) || inside_medium) {
            // Tentative collisions at rate `majorant` (delta tracking with
            // null collisions; weighted so that rgb coefficients may differ).
            float t0 = 0.0, t1 = t_hit;
            vec3 extinction = inside_medium ? s.inside_extinction : medium.sigma_s.rgb + medium.sigma_a.rgb;
            float majorant = inside_medium ? max(extinction.r, max(extinction.g, extinction.b)) : medium_majorant();
            float g = inside_medium ? s.inside_scattering.w : medium.sigma_s.w;
            bool event = false;
            if (majorant > 0.0 && (inside_medium || clip_to_medium(s.origin, s.dir, t0, t1))) {
                float t = t0;
                for (int i = 0; i < 100000; ++i) {
                    t -= log(1.0 - rng_next(rng)) / majorant;
                    if (t >= t1) break;
                    vec3 x = s.origin + t * s.dir;
                    float density = inside_medium ? 1.0 : medium_density(x);
                    vec3 sigma_s = (inside_medium ? s.inside_scattering.rgb : medium.sigma_s.rgb) * density;
                    vec3 sigma_n = vec3(majorant) - extinction * density;
                    // Every tentative collision connects: E[sum] = integral of T sigma_s along the ray.
                    if (any(greaterThan(sigma_s, vec3(0.0)))) {
                        uint tag = tag_for(specular, scattered_or_bounced, true);
                        // Straight from a sampled light: airlight, which
                        // camera.comp samples along the camera rays.
                        // Multiple scattering (tag `other`) seen directly is
                        // the volume gather (volume_points.comp) when the volume photon
                        // map is on (finite variance near the eye); so is
                        // every collision inside a dielectric: an eye that
                        // sees it directly is under the same surface, in
                        // water lit all around it, where the connections'
                        // 1/d^2 made the image fireflies.
                        bool gathered_on_first_segment = pc.volume_capacity != 0u
                            && (tag == COMPONENT_OTHER || inside_medium);
                        if (!straight_from_sampled_light && !gathered_on_first_segment) {
                            connect_medium(s, x, s.weight * sigma_s / majorant, g, tag, rng);
                        }
                        if (pc.volume_capacity != 0u) store_volume_photon(x, s.dir, s.weight * sigma_s / majorant, tag);
                    }
                    float p_scatter = (sigma_s.r + sigma_s.g + sigma_s.b) / (3.0 * majorant);
                    float p_null = max(sigma_n.r + sigma_n.g + sigma_n.b, 0.0) / (3.0 * majorant);
                    float u = rng_next(rng);
                    if (u < p_scatter) {
                        s.weight *= sigma_s / (majorant * p_scatter);
                        s.origin = x;
                        s.dir = sample_hg(s.dir, g, vec2(rng_next(rng), rng_next(rng)));
                        scattered_or_bounced = true;
                        event = true;
                        break;
                    } else if (u < p_scatter + p_null) {
                        s.weight *= sigma_n / (majorant * p_null);
                    } else {
                        return; // absorbed
                    }
                }
            }
            if (event) continue;
        }
        if (!found) return;

        vec3 x = s.origin + hit.t * s.dir;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        // Inside a dielectric without scattering: Beer-Lambert (with
        // scattering, the free-flight sampling above attenuated the photon).
        if (s.inside && !inside_medium) s.weight *= exp(-s.inside_extinction * hit.t);

        Material m = materials[hit_material(hit)];
        if (floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE) {
            vec3 ng_in = front ? ng : -ng; // the side the photon arrives on
            uint tag = tag_for(specular, scattered_or_bounced, false);
            vec3 albedo = hit_albedo(hit);
            // A photon straight from a light camera.comp samples is direct
            // light (L D), which it samples by shadow rays at every pixel's
            // diffuse point, seen directly or through a specular chain: it
            // is neither connected nor gathered. Every other photon is both.
            if (!straight_from_sampled_light) {
                connect_surface(s, x, ng_in, albedo, tag, rng);
                if (pc.gather != 0u) gather_surface(x, ng_in, s.weight, tag);
            }
            // The photon goes on by a `mixed` material's mirror part with
            // probability lum(specular), or diffusely (while diffuse bounces
            // are left) with lum(albedo) (a plain diffuse surface:
            // clamp(lum(albedo), 0.05, 1)), else stops; dividing the weight
            // by the probability of the choice keeps the estimate unbiased
            // (Russian roulette over the two lobes; their sum is at most 1).
            vec3 mirror = m.specular.rgb;
            float p_mirror = luminance(mirror);
            float p_diffuse = diffuse_left == 0u ? 0.0
                : p_mirror > 0.0 ? luminance(albedo) : clamp(luminance(albedo), 0.05, 1.0);
            float u = rng_next(rng);
            if (u < p_mirror) {
                s.weight /= p_mirror;
                mirror_bounce(s, x, ng, hit_normal(hit), front, mirror);
                specular += 1u;
            } else if (u < p_mirror + p_diffuse) {
                diffuse_left -= 1u;
                s.weight *= albedo / p_diffuse;
                s.dir = cosine_hemisphere(vec2(rng_next(rng), rng_next(rng)), ng_in);
                s.origin = offset_origin(x, ng_in);
                scattered_or_bounced = true;
            } else {
                return;
            }
        } else {
            specular_bounce(s, x, ng, hit_normal(hit), front, m, rng_next(rng), false);
            specular += 1u;
        }
        if (luminance(s.weight) <= 0.0) return;
    }
}

void main() {
    trace_photon();
    // The aim guide's count: 1/g, so that a cell's sum estimates its useful
    // photons under uniform aiming.
    if (guide_light != GUIDE_UNAIMED && photon_useful) {
        atomicAdd(aim_guide[guide_index(guide_light, GUIDE_COUNTS, guide_photon_cell)], 1.0 / guide_photon_density);
    }
}
