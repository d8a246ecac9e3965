//! The glow renderer of the 3D view, called from an egui paint callback. It needs OpenGL 3 or
//! WebGL2 (GLSL 1.40 / ES 3.00): one shader, three vertex buffers (opaque triangles, lines,
//! translucent triangles), re-uploaded only when the scene's generation changes.
use std::sync::Arc;

use eframe::egui_glow::ShaderVersion;
use eframe::glow::{self, HasContext};
use glam::{Mat4, Vec3};

use crate::scene::{Geometry, VERTEX_FLOATS};

/// What one frame draws.
pub struct Frame {
    /// Changes whenever `geometry` does.
    pub generation: u64,
    /// The vertex arrays.
    pub geometry: Arc<Geometry>,
    /// Projection times view.
    pub view_projection: Mat4,
    /// Unit vector towards the light (a headlight: from the eye).
    pub light: Vec3,
}

struct Buffer {
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    count: i32,
}

/// GPU state of the 3D view.
pub struct Renderer {
    program: glow::Program,
    u_mvp: Option<glow::UniformLocation>,
    u_light: Option<glow::UniformLocation>,
    u_lit: Option<glow::UniformLocation>,
    buffers: [Buffer; 3],
    uploaded: Option<u64>,
}

// SAFETY: egui's paint callbacks, which own the renderer, must be `Send`. In the page's threaded
// build (`threads`, WebAssembly atomics) wasm-bindgen's handles to WebGL objects are not, as a
// handle is only valid on the thread that made it. The renderer is made and used only inside
// those callbacks, which eframe runs on the page's main thread, the one owning the WebGL
// context; no other thread ever touches it (the core's Web Workers get none of the app's state).
#[cfg(all(target_arch = "wasm32", target_feature = "atomics"))]
unsafe impl Send for Renderer {}

const VERTEX_SHADER: &str = r#"
uniform mat4 u_mvp;
in vec3 a_pos;
in vec3 a_normal;
in vec4 a_color;
out vec3 v_normal;
out vec4 v_color;
void main() {
    gl_Position = u_mvp * vec4(a_pos, 1.0);
    v_normal = a_normal;
    v_color = a_color;
}
"#;

// Two-sided headlight shading: meshes may be oriented either way.
const FRAGMENT_SHADER: &str = r#"
uniform vec3 u_light;
uniform float u_lit;
in vec3 v_normal;
in vec4 v_color;
out vec4 out_color;
void main() {
    float d = abs(dot(normalize(v_normal + vec3(1e-9)), u_light));
    float shade = mix(1.0, 0.3 + 0.7 * d, u_lit);
    out_color = vec4(v_color.rgb * shade, v_color.a);
}
"#;

fn header(gl: &glow::Context) -> Result<&'static str, String> {
    match ShaderVersion::get(gl) {
        ShaderVersion::Es300 => Ok("#version 300 es\nprecision highp float;\n"),
        ShaderVersion::Gl140 => Ok("#version 140\n"),
        other => Err(format!(
            "the 3D view needs OpenGL 3 or WebGL2 (found {other:?})"
        )),
    }
}

impl Renderer {
    /// Compiles the shader and creates the buffers.
    ///
    /// # Errors
    ///
    /// The driver's message when a shader does not compile or link, or a buffer cannot be
    /// created.
    pub fn new(gl: &glow::Context) -> Result<Self, String> {
        let header = header(gl)?;
        // SAFETY: plain OpenGL calls on the context egui hands to the paint callback; every
        // object created here is owned by the renderer and freed in `destroy`.
        unsafe {
            let program = gl.create_program()?;
            let mut shaders = Vec::new();
            for (kind, src) in [
                (glow::VERTEX_SHADER, VERTEX_SHADER),
                (glow::FRAGMENT_SHADER, FRAGMENT_SHADER),
            ] {
                let s = gl.create_shader(kind)?;
                gl.shader_source(s, &format!("{header}{src}"));
                gl.compile_shader(s);
                if !gl.get_shader_compile_status(s) {
                    return Err(format!("shader: {}", gl.get_shader_info_log(s)));
                }
                gl.attach_shader(program, s);
                shaders.push(s);
            }
            for (i, name) in ["a_pos", "a_normal", "a_color"].iter().enumerate() {
                gl.bind_attrib_location(program, i as u32, name);
            }
            gl.link_program(program);
            if !gl.get_program_link_status(program) {
                return Err(format!("shader link: {}", gl.get_program_info_log(program)));
            }
            for s in shaders {
                gl.detach_shader(program, s);
                gl.delete_shader(s);
            }
            let buffer = || -> Result<Buffer, String> {
                let vao = gl.create_vertex_array()?;
                let vbo = gl.create_buffer()?;
                gl.bind_vertex_array(Some(vao));
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
                let stride = (VERTEX_FLOATS * 4) as i32;
                for (i, (size, offset)) in [(3, 0), (3, 3), (4, 6)].into_iter().enumerate() {
                    gl.enable_vertex_attrib_array(i as u32);
                    gl.vertex_attrib_pointer_f32(
                        i as u32,
                        size,
                        glow::FLOAT,
                        false,
                        stride,
                        offset * 4,
                    );
                }
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
                Ok(Buffer { vao, vbo, count: 0 })
            };
            Ok(Self {
                u_mvp: gl.get_uniform_location(program, "u_mvp"),
                u_light: gl.get_uniform_location(program, "u_light"),
                u_lit: gl.get_uniform_location(program, "u_lit"),
                program,
                buffers: [buffer()?, buffer()?, buffer()?],
                uploaded: None,
            })
        }
    }

    fn upload(&mut self, gl: &glow::Context, g: &Geometry) {
        let data = [&g.opaque, &g.lines, &g.translucent];
        for (b, d) in self.buffers.iter_mut().zip(data) {
            // SAFETY: the buffer belongs to this renderer; the data is copied by the driver.
            unsafe {
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(b.vbo));
                gl.buffer_data_u8_slice(
                    glow::ARRAY_BUFFER,
                    bytemuck::cast_slice(d.as_slice()),
                    glow::DYNAMIC_DRAW,
                );
            }
            b.count = (d.len() / VERTEX_FLOATS) as i32;
        }
        // SAFETY: unbinding is always valid.
        unsafe { gl.bind_buffer(glow::ARRAY_BUFFER, None) };
    }

    /// Draws `frame` into the current viewport (set by egui to the view's rectangle; the
    /// scissor is its clip rectangle, so the depth clear stays inside the view).
    pub fn paint(&mut self, gl: &glow::Context, frame: &Frame) {
        if self.uploaded != Some(frame.generation) {
            self.upload(gl, &frame.geometry);
            self.uploaded = Some(frame.generation);
        }
        // SAFETY: state changes and draws on our own objects; egui restores its state after
        // the callback, and we leave the depth mask as egui expects it.
        unsafe {
            gl.use_program(Some(self.program));
            gl.uniform_matrix_4_f32_slice(
                self.u_mvp.as_ref(),
                false,
                &frame.view_projection.to_cols_array(),
            );
            gl.uniform_3_f32(
                self.u_light.as_ref(),
                frame.light.x,
                frame.light.y,
                frame.light.z,
            );
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LEQUAL);
            gl.depth_mask(true);
            gl.clear_depth_f32(1.0);
            gl.clear(glow::DEPTH_BUFFER_BIT);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::BLEND);

            let [opaque, lines, translucent] = &self.buffers;
            gl.uniform_1_f32(self.u_lit.as_ref(), 1.0);
            draw(gl, opaque, glow::TRIANGLES);
            gl.uniform_1_f32(self.u_lit.as_ref(), 0.0);
            draw(gl, lines, glow::LINES);

            gl.uniform_1_f32(self.u_lit.as_ref(), 1.0);
            gl.enable(glow::BLEND);
            gl.blend_func_separate(
                glow::SRC_ALPHA,
                glow::ONE_MINUS_SRC_ALPHA,
                glow::ONE,
                glow::ONE_MINUS_SRC_ALPHA,
            );
            gl.depth_mask(false);
            draw(gl, translucent, glow::TRIANGLES);
            gl.depth_mask(true);

            gl.disable(glow::DEPTH_TEST);
            gl.bind_vertex_array(None);
            gl.use_program(None);
        }
    }

    /// Frees the GPU objects.
    pub fn destroy(&self, gl: &glow::Context) {
        // SAFETY: the objects are ours and no longer used after this.
        unsafe {
            gl.delete_program(self.program);
            for b in &self.buffers {
                gl.delete_vertex_array(b.vao);
                gl.delete_buffer(b.vbo);
            }
        }
    }
}

/// # Safety
/// `b` must belong to the current context.
unsafe fn draw(gl: &glow::Context, b: &Buffer, mode: u32) {
    if b.count > 0 {
        gl.bind_vertex_array(Some(b.vao));
        gl.draw_arrays(mode, 0, b.count);
    }
}
