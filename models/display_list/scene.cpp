#include "models/display_list/scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

namespace pp5 {

glm::mat4 view_matrix(const Camera& camera) {
  return glm::lookAt(camera.eye, camera.target, camera.up);
}

glm::mat4 projection_matrix(const Camera& camera, float aspect) {
  return glm::perspective(glm::radians(camera.fov_y_degrees), aspect, camera.near_plane,
                          camera.far_plane);
}

}  // namespace pp5
