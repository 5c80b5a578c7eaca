//! CPU mirrors of the GPU structs in glsl/common.glsl (std140 / std430 layouts).

use crate::scene::{AlphaMode, Light, LightKind, Material, TexRef};
use glam::{Mat4, Vec3, Vec4};
use std::collections::HashMap;

/// Reinterprets plain-old-data as bytes for upload.
pub fn as_bytes<T: Copy>(data: &[T]) -> &[u8] {
    // SAFETY: T is Copy plain data with repr(C) layout; the slice covers exactly its memory.
    unsafe { std::slice::from_raw_parts(data.as_ptr() as *const u8, std::mem::size_of_val(data)) }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameUniforms {
    pub view_proj: Mat4,
    pub view: Mat4,
    pub proj: Mat4,
    pub eye: Vec4,
    /// lights, width, height, shadow views
    pub counts: [u32; 4],
    /// shadow-map resolution, normal offset in texels, PCF radius in texels, unused
    pub shadow: Vec4,
    /// the area lights' shadow-map resolution, their first view, the widest soft-shadow
    /// filter's half width in texels, unused
    pub area_shadow: Vec4,
    /// voxel grid origin, edge length
    pub grid: Vec4,
    /// resolution, bounces, diffuse cone count, flags
    pub grid_info: [u32; 4],
    /// diffuse aperture (tan of half angle), step factor, max distance (fraction of the grid),
    /// emission fixed-point scale
    pub cone: Vec4,
    /// start offset (voxels), AO falloff (per metre), specular on, debug mip
    pub trace: Vec4,
    /// diffuse cones: direction around +Z, weight
    pub cones: [Vec4; 16],
    /// levels finer than the cone diameter to sample, unused x3
    pub tuning: Vec4,
    /// the environment: strength, cosine and sine of its turn, 1 when there is one
    pub env: Vec4,
    /// the bounces' diffuse cones: aperture (tan of half angle), count, unused x2
    pub bounce_cone: Vec4,
    /// the bounces' diffuse cones: direction around +Z, weight
    pub bounce_cones: [Vec4; 16],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct GpuMaterial {
    pub base_color: Vec4,
    pub emissive: Vec4,
    pub specular: Vec4,
    pub params: Vec4,
    pub tex0: [i32; 4],
    pub tex1: [i32; 4],
}

fn tex(t: &Option<TexRef>) -> i32 {
    t.map(|t| t.texture as i32).unwrap_or(-1)
}

impl GpuMaterial {
    pub fn from_material(m: &Material) -> Self {
        let cutoff = match m.alpha_mode {
            AlphaMode::Mask(c) => c,
            // BLEND is drawn opaque: the renderer has no transparency pass.
            AlphaMode::Opaque | AlphaMode::Blend => -1.0,
        };
        GpuMaterial {
            base_color: m.base_color,
            emissive: m.emissive.extend(0.0),
            specular: m.specular_color.extend(m.specular_factor),
            params: Vec4::new(m.metallic, m.roughness, m.normal_scale, cutoff),
            tex0: [
                tex(&m.base_color_tex),
                tex(&m.metallic_roughness_tex),
                tex(&m.normal_tex),
                tex(&m.emissive_tex),
            ],
            tex1: [
                tex(&m.specular_tex),
                tex(&m.specular_color_tex),
                m.double_sided as i32,
                0,
            ],
        }
    }
}

pub const LIGHT_DIRECTIONAL: f32 = 0.0;
pub const LIGHT_POINT: f32 = 1.0;
pub const LIGHT_SPOT: f32 = 2.0;
/// An emissive surface as an area light (render/area_lights.rs).
pub const LIGHT_AREA: f32 = 3.0;
/// The lights a scene may have, area lights included (glsl/common.glsl: MAX_LIGHTS; a uniform
/// block of 16 KiB).
pub const MAX_LIGHTS: usize = 256;
/// The shadow views (six per point or area light), in a uniform block of 64 KiB
/// (glsl/common.glsl: MAX_SHADOW_VIEWS).
pub const MAX_SHADOW_VIEWS: usize = 819;
/// glsl/area_lights.glsl: AREA_POLYGON, AREA_SPHERE.
pub const AREA_POLYGON: u32 = 0;
pub const AREA_SPHERE: u32 = 1;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct GpuLight {
    pub position_type: Vec4,
    pub direction_range: Vec4,
    pub radiance: Vec4,
    /// angle scale, angle offset, first shadow view, shadow view count; for an emitter
    /// (radiance.w 1 when two-sided): lobe area, uniform area, first view, view count
    pub cone: Vec4,
}

impl GpuLight {
    pub fn from_light(l: &Light, first_view: u32, views: u32) -> Self {
        let (ty, scale, offset) = match l.kind {
            LightKind::Directional => (LIGHT_DIRECTIONAL, 0.0, 0.0),
            LightKind::Point => (LIGHT_POINT, 0.0, 0.0),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                // KHR_lights_punctual's recommended falloff; the 0.001 floor keeps inner == outer
                // finite (a hard edge).
                let scale = 1.0 / (inner_cone.cos() - outer_cone.cos()).max(0.001);
                (LIGHT_SPOT, scale, -outer_cone.cos() * scale)
            }
        };
        GpuLight {
            position_type: l.position.extend(ty),
            direction_range: l.direction.extend(l.range.unwrap_or(0.0)),
            radiance: l.radiance.extend(0.0),
            cone: Vec4::new(scale, offset, first_view as f32, views as f32),
        }
    }

    /// An area light whose polygons and edges are `range` of the area tables.
    pub fn from_area(
        l: &super::area_lights::AreaLight,
        range: &AreaRange,
        first_view: u32,
        views: u32,
    ) -> Self {
        GpuLight {
            position_type: l.position.extend(LIGHT_AREA),
            direction_range: Vec4::new(
                l.apparent_radius(),
                range.first_edge as f32,
                range.edges as f32,
                l.radius,
            ),
            radiance: l.emission.extend(if l.two_sided { 1.0 } else { 0.0 }),
            cone: Vec4::new(
                range.first_polygon as f32,
                range.polygons as f32,
                first_view as f32,
                views as f32,
            ),
        }
    }
}

/// glsl/area_lights.glsl: AreaPolygon.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct GpuAreaPolygon {
    /// Front normal, and its dot with the polygon's points.
    pub plane: Vec4,
    /// First vertex, vertex count, kind (AREA_POLYGON, AREA_SPHERE), unused.
    pub range: [u32; 4],
}

/// glsl/area_lights.glsl: AreaEdge. An edge of a light's outlines between corners `a` and
/// `b` (indices into the corners), running a to b in polygon `left` and b to a in polygon
/// `right` (NO_POLYGON when no other polygon has it).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuAreaEdge {
    pub a: u32,
    pub b: u32,
    pub left: u32,
    pub right: u32,
}

pub const NO_POLYGON: u32 = u32::MAX;

/// Where one area light's entries lie in the area tables.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AreaRange {
    pub first_polygon: u32,
    pub polygons: u32,
    pub first_edge: u32,
    pub edges: u32,
}

/// The area lights' tables, in light order.
#[derive(Clone, Debug, Default)]
pub struct AreaTables {
    pub ranges: Vec<AreaRange>,
    pub polygons: Vec<GpuAreaPolygon>,
    /// Polygon corners; a sphere's single entry is its centre and radius.
    pub vertices: Vec<Vec4>,
    /// The polygons' edges, each once: where two polygons of a light share an edge (a box's
    /// faces), a point that sees both from the front has its terms cancel, so the edges
    /// between a face it sees and one it does not (the silhouette) are all it sums.
    pub edges: Vec<GpuAreaEdge>,
}

/// The edges of polygons `polys`, whose corners start at `first_corner` and polygons at
/// `first_polygon`, each shared edge once (corners equal bit for bit: the outlines come from
/// welded points, placed by the same transform). A corner several polygons share is named by
/// its first index, so the shader chains edges by index.
fn polygon_edges(
    polys: &[super::area_lights::Polygon],
    first_corner: u32,
    first_polygon: u32,
) -> Vec<GpuAreaEdge> {
    let key = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut edges: Vec<GpuAreaEdge> = Vec::new();
    let mut open: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
    let mut names: HashMap<[u32; 3], u32> = HashMap::new();
    let mut corner = first_corner;
    for (i, p) in polys.iter().enumerate() {
        let n = p.vertices.len();
        for k in 0..n {
            let (va, vb) = (p.vertices[k], p.vertices[(k + 1) % n]);
            let a = *names.entry(key(va)).or_insert(corner + k as u32);
            let b = *names
                .entry(key(vb))
                .or_insert(corner + ((k + 1) % n) as u32);
            let polygon = first_polygon + i as u32;
            // Its twin runs b to a in a polygon before this one.
            if let Some(e) = open.remove(&(key(vb), key(va))) {
                edges[e].right = polygon;
                continue;
            }
            open.insert((key(va), key(vb)), edges.len());
            edges.push(GpuAreaEdge {
                a,
                b,
                left: polygon,
                right: NO_POLYGON,
            });
        }
        corner += n as u32;
    }
    edges
}

/// The area lights' polygons, corners and edges (a sphere: one corner, its centre and radius,
/// and no edges), in light order.
pub fn area_tables(lights: &[super::area_lights::AreaLight]) -> AreaTables {
    use super::area_lights::Shape;
    let mut t = AreaTables::default();
    for l in lights {
        let first = t.polygons.len() as u32;
        let first_edge = t.edges.len() as u32;
        let (polygons, vertices) = (&mut t.polygons, &mut t.vertices);
        match &l.shape {
            Shape::Polygons(polys) => {
                let edges = polygon_edges(polys, vertices.len() as u32, first);
                for p in polys {
                    polygons.push(GpuAreaPolygon {
                        plane: p.normal.extend(p.normal.dot(p.vertices[0])),
                        range: [
                            vertices.len() as u32,
                            p.vertices.len() as u32,
                            AREA_POLYGON,
                            0,
                        ],
                    });
                    vertices.extend(p.vertices.iter().map(|v| v.extend(1.0)));
                }
                t.edges.extend(edges);
            }
            Shape::Sphere { centre, radius } => {
                polygons.push(GpuAreaPolygon {
                    plane: Vec4::ZERO,
                    range: [vertices.len() as u32, 1, AREA_SPHERE, 0],
                });
                vertices.push(centre.extend(*radius));
            }
        }
        t.ranges.push(AreaRange {
            first_polygon: first,
            polygons: t.polygons.len() as u32 - first,
            first_edge,
            edges: t.edges.len() as u32 - first_edge,
        });
    }
    t
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadowView {
    pub view_proj: Mat4,
    /// 1 if perspective; texel size (metres for ortho, per metre of depth for perspective)
    pub info: Vec4,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::reflect::{shader_interface, Struct};

    /// (field, offset, size) of each named field of a Rust struct.
    macro_rules! fields {
        ($t:ty { $($f:ident),* $(,)? }) => {
            [$((
                stringify!($f),
                std::mem::offset_of!($t, $f),
                size_of_field(|s: &$t| &s.$f),
            )),*]
        };
    }

    fn size_of_field<T, F>(_: impl Fn(&T) -> &F) -> usize {
        std::mem::size_of::<F>()
    }

    /// The Rust mirror has the GLSL struct's members, in order, at its offsets and sizes, and
    /// its size is the struct's stride in an array (std430) or the block's size.
    fn same_layout(glsl: &Struct, rust: &[(&str, usize, usize)], rust_size: usize) {
        let g: Vec<(&str, usize, usize)> = glsl
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.offset as usize, m.size as usize))
            .collect();
        assert_eq!(g, rust, "{}: GLSL (left) against Rust (right)", glsl.name);
        assert_eq!(glsl.size as usize, rust_size, "{}: size", glsl.name);
    }

    fn glsl_struct(shader: &str, name: &str) -> Struct {
        shader_interface(shader)
            .unwrap()
            .struct_named(name)
            .unwrap_or_else(|| panic!("{shader} has no struct {name}"))
            .clone()
    }

    #[test]
    fn frame_uniforms_match_the_glsl_frame_block() {
        same_layout(
            &glsl_struct("deferred_lighting.comp", "Frame"),
            &fields!(FrameUniforms {
                view_proj,
                view,
                proj,
                eye,
                counts,
                shadow,
                area_shadow,
                grid,
                grid_info,
                cone,
                trace,
                cones,
                tuning,
                env,
                bounce_cone,
                bounce_cones
            }),
            std::mem::size_of::<FrameUniforms>(),
        );
    }

    #[test]
    fn scene_structs_match_the_glsl_structs() {
        same_layout(
            &glsl_struct("gbuffer.frag", "Material"),
            &fields!(GpuMaterial {
                base_color,
                emissive,
                specular,
                params,
                tex0,
                tex1
            }),
            std::mem::size_of::<GpuMaterial>(),
        );
        same_layout(
            &glsl_struct("deferred_lighting.comp", "Light"),
            &fields!(GpuLight {
                position_type,
                direction_range,
                radiance,
                cone
            }),
            std::mem::size_of::<GpuLight>(),
        );
        same_layout(
            &glsl_struct("deferred_lighting.comp", "ShadowView"),
            &fields!(ShadowView { view_proj, info }),
            std::mem::size_of::<ShadowView>(),
        );
        same_layout(
            &glsl_struct("deferred_lighting.comp", "AreaPolygon"),
            &fields!(GpuAreaPolygon { plane, range }),
            std::mem::size_of::<GpuAreaPolygon>(),
        );
        same_layout(
            &glsl_struct("deferred_lighting.comp", "AreaEdge"),
            &fields!(GpuAreaEdge { a, b, left, right }),
            std::mem::size_of::<GpuAreaEdge>(),
        );
    }

    fn square(c: Vec3, u: Vec3, v: Vec3) -> super::super::area_lights::Polygon {
        super::super::area_lights::Polygon {
            vertices: vec![c - u - v, c + u - v, c + u + v, c - u + v],
            normal: u.cross(v).normalize(),
        }
    }

    #[test]
    fn a_box_has_twelve_shared_edges_and_a_quad_four_of_its_own() {
        let quad = [square(Vec3::ZERO, Vec3::X, Vec3::Z)];
        let edges = polygon_edges(&quad, 10, 3);
        assert_eq!(edges.len(), 4);
        assert!(edges.iter().all(|e| e.left == 3 && e.right == NO_POLYGON));
        assert_eq!(
            edges.iter().map(|e| (e.a, e.b)).collect::<Vec<_>>(),
            [(10, 11), (11, 12), (12, 13), (13, 10)]
        );
        let faces: Vec<_> = (0..3)
            .flat_map(|axis| {
                [-1.0f32, 1.0].map(|sign| {
                    let n = Vec3::AXES[axis] * sign;
                    let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
                    let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
                    square(n, u, v)
                })
            })
            .collect();
        let edges = polygon_edges(&faces, 0, 0);
        assert_eq!(edges.len(), 12);
        assert!(edges
            .iter()
            .all(|e| e.right != NO_POLYGON && e.left != e.right));
        // Eight corners, each named once, three edges at each.
        let mut names: Vec<u32> = edges.iter().flat_map(|e| [e.a, e.b]).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 8);
        for n in names {
            let at = edges.iter().filter(|e| e.a == n || e.b == n).count();
            assert_eq!(at, 3, "corner {n}");
        }
    }

    #[test]
    fn a_layout_that_drifts_is_caught() {
        // Two members swapped on the Rust side.
        let glsl = glsl_struct("deferred_lighting.comp", "ShadowView");
        let swapped = std::panic::catch_unwind(|| {
            same_layout(
                &glsl,
                &[("info", 64, 16), ("view_proj", 0, 64)],
                std::mem::size_of::<ShadowView>(),
            )
        });
        assert!(swapped.is_err());
    }
}
