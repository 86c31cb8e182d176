#pragma once
// The sphere primitive on the GP: a sphere drawn with the expression evaluator's quadratic
// terms, as Pixel-Planes drew them, instead of a tessellation.
//
// The geometry (eye at the origin looking down -z; pixel (X, Y) has its centre at screen
// (X + 0.5, Y + 0.5), y down). The ray through pixel (X, Y) is d = (ax X + bx, ay Y + by, -1),
// affine in X and Y (projection_matrix's P00, P11). With the sphere's eye-space centre c and
// radius r, and k = |c|^2 - r^2 > 0 (the eye outside the sphere):
//  - Coverage. The ray meets the sphere iff Q = (d.c)^2 - k |d|^2 >= 0: the cone from the eye
//    tangent to the sphere. Q is a quadratic in X and Y (the outline is a conic, an ellipse for
//    a sphere wholly in front of the eye), so the evaluator's quadratic terms give the inside
//    test exactly, at every pixel centre, in real arithmetic (`sphere_inside`).
//  - Depth. The near hit is at view-axis distance t with 1/t = (d.c + sqrt(Q)) / k, and the
//    depth buffer holds G - H / t (G, H from the projection, as for triangles), so
//        depth = G - (H / k) (d.c + sqrt(Q)):
//    linear but for sqrt(Q). Over the disc Q runs from 0 to its maximum Qm (at the conic's
//    centre); `sphere_depth` replaces sqrt(Q) by its minimax straight line in Q,
//    Q / sqrt(Qm) + sqrt(Qm) / 8, whose error is at most sqrt(Qm) / 8 (equioscillating at
//    Q = 0, Qm / 4 and Qm). The depth error is therefore at most (H / k) sqrt(Qm) / 8 depth
//    units, plus the fixed-point rounding below: ScreenSphere::depth_bound.
//    Pixel-Planes 4 drew the line through the ends, Q / sqrt(Qm), with no offset: a paraboloid
//    exact at the outline and the nearest point, too deep by up to sqrt(Qm) / 4 between
//    (`sphere_depth_paraboloid`; H. Fuchs et al., "Fast spheres, shadows, textures,
//    transparencies, and image enhancements in Pixel-planes", SIGGRAPH 1985).
//    The exact depth instead takes the square root in pixel memory (sphere_sqrt.pp5): the GP
//    sends the linear part G - (H / k) d.c (`sphere_depth_base`) and the radicand
//    (H / k)^2 Q / 4^n (`sphere_radicand`), n (`sphere_root_shift`) the least shift keeping
//    its root below 2^13 - 1 (kSphereRootBits), so that it fits the evaluator's integer bits
//    (26 of the 28 that 40 result bits less 12 fraction bits leave); the firmware subtracts
//    2^n times the truncated root. The error is at most 2^(n - 1) + 1/2 units plus the
//    fixed-point rounding: a relief of 2^22 units (n = 9) is drawn to within 257 units.
//  - Shading inputs. `sphere_nx/ny/nz` are 127 times the eye-space normal (p - c) / r at the
//    hit p = t d, each fitted by least squares with a quadratic over 13 fixed points of the
//    unit disc mapped onto the ellipse (the centre, 6 at radius 0.55, 6 at 0.92); the fit's
//    error is measured, not bounded (pp5sim spheres reports it). The fit overshoots a unit
//    normal by up to 5.6% at the centre (the largest length of the fitted parallel-projection
//    normal over the disc, computed once); the values are scaled so that the fitted vector
//    stays within 129, the longest whose N.L with a 127-long light vector fits the 14 bits
//    the lighting reads (phong.pp5's `dot[13:6]`): normals come out up to 4% short, which
//    dims the specular highlight (power 16). The firmware clamps each component to +-127
//    before storing it in an 8-bit field.
//
// Fixed point (evaluator.fraction_bits F, coefficient_bits, result_bits R). Every quadratic is
// first written about an anchor pixel (x0, y0), the projected centre: q = a dx^2 + b dx dy +
// c dy^2 + d dx + e dy + f with dx = X - x0. Each of a..f, times the scale (2^F for depth and
// normals, 2^s for the conic), is rounded to the nearest integer, and the result is expanded
// to A X^2 + B XY + C Y^2 + D X + E Y + F in exact integer arithmetic. The value the evaluator
// delivers at pixel (X, Y) then differs from scale * q by at most
//     e(X, Y) = (dx^2 + |dx dy| + dy^2 + |dx| + |dy| + 1) / 2,
// small near the anchor whatever the distance to the screen's origin. The conic's scale 2^s
// is the largest power of two keeping |2^s Q| <= 2^(R - 3) over every pixel of every region
// the sphere is binned to, so the evaluator's sum cannot wrap on a pixel it tests; its inside
// test equals the exact one wherever |2^s Q| > e(X, Y). When the evaluator wraps at no more
// bits than a coefficient holds (R <= coefficient_bits), each coefficient is sent modulo
// 2^coefficient_bits (every monomial has an integer multiplier, so the values are unchanged
// modulo 2^R); otherwise a coefficient that does not fit drops the sphere (counted as
// coefficient overflow).
//
// Culling (SetupCounts): a sphere wholly behind the eye is `sphere_behind`; one reaching in
// front of the near plane (or containing the eye) is `sphere_near`, and one reaching beyond
// the far plane `sphere_far` (their depth would leave the depth range); wholly in front of the
// near plane or beyond the far one it is `clipped_away`; one whose ellipse holds no pixel
// centre of the screen is `no_pixels`. All are dropped and counted; none is drawn partly.
//
// Contract: project() is a pure function of the sphere, the camera and the GeometryParams;
// the expressions (models/gp/expressions.cpp, the sphere_* entries) read only the ScreenSphere.
#include <array>
#include <cstdint>
#include <glm/glm.hpp>

#include "firmware/isa/interface.hpp"
#include "firmware/isa/types.hpp"
#include "models/display_list/scene.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"

namespace pp5 {

// a dx^2 + b dx dy + c dy^2 + d dx + e dy + f, dx = X - x0, dy = Y - y0 (the ScreenSphere's
// anchor).
struct CentredQuadratic {
  double a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  double at(double dx, double dy) const {
    return a * dx * dx + b * dx * dy + c * dy * dy + d * dx + e * dy + f;
  }
};

struct ScreenSphere {
  int source = 0;          // index in Scene::spheres
  bool far = false;        // the far hemisphere (depth and normal of the far hit)
  glm::dvec3 centre{0.0};  // eye space
  double radius = 1;
  glm::dvec3 color{0.0};
  std::int64_t x0 = 0, y0 = 0;             // anchor pixel
  CentredQuadratic conic;                  // Q, >= 0 inside
  int conic_shift = 0;                     // the conic's scale is 2^conic_shift
  CentredQuadratic depth;                  // depth units
  CentredQuadratic paraboloid;             // depth units, Pixel-Planes 4's (no offset)
  std::array<CentredQuadratic, 3> normal;  // 127 * the normal's x, y, z
  // The exact depth in pixel memory: depth_base -+ 2^root_shift sqrt(radicand) (near: -).
  CentredQuadratic depth_base;           // linear, depth units, half a root step folded in
  CentredQuadratic radicand;             // (H / k)^2 Q / 4^root_shift, depth units^2 / 4^root_shift
  int root_shift = 0;                    // 0..11: the root stays below 2^kSphereRootBits - 1
  double centre_x = 0, centre_y = 0;     // the conic's centre, relative to the anchor
  double q_max = 0;                      // Q at the centre
  double depth_approximation_bound = 0;  // (H / k) sqrt(Qm) / 8
  double depth_bound = 0;                // the above + rounding over the bounding box + 1 (floor)
  int x_min = 0, x_max = -1, y_min = 0, y_max = -1;  // pixel-centre bounding box, inclusive
};

// (dx^2 + |dx dy| + dy^2 + |dx| + |dy| + 1) / 2: the fixed-point rounding bound above.
double sphere_rounding_bound(double dx, double dy);

// True for the expressions only a sphere supplies (sphere_*).
bool is_sphere_expression(Expression e);

// The camera's side of the sphere geometry, built once per frame.
class SphereProjector {
 public:
  SphereProjector(const GeometryParams& params, const Camera& camera);
  // Project world-space sphere `index` of `spheres`; false (and counted) if it is dropped.
  // With `far`, its far hemisphere: the depth of the far hit and the normal there turned to
  // the eye (a sphere of a solid, seen from inside by a complemented CSG literal).
  bool project(const Sphere& sphere, int index, ScreenSphere& out, SetupCounts& counts,
               bool far = false) const;
  // The ray through pixel index (x, y) (fractions allowed), eye space, d.z = -1.
  glm::dvec3 ray(double x, double y) const { return {ax_ * x + bx_, ay_ * y + by_, -1.0}; }
  // Depth units at view-axis distance t (as GeometryEngine maps a triangle's vertices).
  double depth_at(double t) const { return g_ - h_ / t; }
  const glm::dmat4& view() const { return view_; }

 private:
  GeometryParams params_;
  glm::dmat4 view_;
  double near_ = 0, far_ = 0;
  double ax_ = 0, bx_ = 0, ay_ = 0, by_ = 0;
  double g_ = 0, h_ = 0;
  double depth_max_ = 0;
};

// The fixed-point coefficients of q about (x0, y0) at `scale` (see above); false if a
// coefficient does not fit and the evaluator does not wrap at coefficient_bits.
bool sphere_fixed_point(const CentredQuadratic& q, double scale, std::int64_t x0, std::int64_t y0,
                        const GeometryParams& params, QuadraticCoefficients& out);

// i860 operations of one sphere (docs/timing.md, "Spheres"): fetch, transform and cull; with
// `setups` 1, the projection (conic, centre, bounding box), the shared normal samples when
// the procedure asks for a normal, each expression's cost, the packet; each region's binning.
OpCounts sphere_operations(const GpWorkload& w, int setups, int regions);

}  // namespace pp5
