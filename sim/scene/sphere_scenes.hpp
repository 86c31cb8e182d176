#pragma once
// Scenes of spheres (the sphere primitive kind, models/gp/sphere.hpp): the built-in `spheres`,
// `molecule` and `spheres-and-triangles`, space-filling molecular models (element radii and
// colours, molecule files read through gemmi), and the tessellation of spheres into meshes
// that `pp5sim spheres` compares the quadric spheres with.
#include <string>
#include <vector>

#include "sim/scene/scene.hpp"

namespace pp5 {

// The names make_sphere_scene accepts.
std::vector<std::string> sphere_scene_names();
// A built-in sphere scene by name; throws std::invalid_argument for another name.
Scene make_sphere_scene(const std::string& name);

// Conventional van der Waals radius (Bondi 1964, Angstrom) and CPK colour (as Jmol draws
// them) of an element given by its symbol (case-insensitive: "C", "FE", "Fe"). An element
// outside the table gets 1.80 Angstrom and Jmol's pink for unknowns.
struct ElementStyle {
  float radius;
  glm::vec3 color;
};
ElementStyle element_style(const std::string& symbol);

// The camera for a scene's meshes and spheres seen from `view_direction` (frame_mesh's
// framing, with each sphere's bounding cube as extra points), near and far bracketing both.
Camera frame_scene(const Mesh& mesh, const std::vector<Sphere>& spheres, glm::vec3 view_direction,
                   float fov_y_degrees);

// Each sphere as a UV sphere of 2 u (v - 1) triangles (u around, v pole to pole; u >= 3,
// v >= 2), appended to `mesh` with the sphere's colour and exact normals.
void append_tessellated_spheres(const std::vector<Sphere>& spheres, int u, int v, Mesh& mesh);

// Atoms of a molecule file (PDB, or mmCIF: .cif/.mmcif, read through gemmi) as spheres of
// element_style's radius and colour, first model only, hydrogens included when present.
// Throws SceneError (scene_loader.hpp) naming the file (and the line, where gemmi gives one)
// for an unreadable or malformed file or one with no atoms.
std::vector<Sphere> read_molecule_file(const std::string& path);
// The same from a file's text; `path` names it in messages, `cif` chooses mmCIF over PDB.
std::vector<Sphere> parse_molecule(const std::string& text, const std::string& path, bool cif);

}  // namespace pp5
