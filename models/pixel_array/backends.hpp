#pragma once
// The pixel backends by name: the registry a Renderer board builds its backend from.
//
// Contract: names are unique; make_pixel_backend(name, params) returns a new backend of that
// kind in its initial state (memory, stack and backing store 0, E = 1) or throws
// std::invalid_argument naming the unknown name and the known ones. Every entry must give
// pixel memory bit-identical to "bit" for every instruction stream (tests/test_isa.cpp runs
// each entry against the reference).
#include <memory>
#include <string>
#include <vector>

#include "firmware/isa/backend.hpp"

namespace pp5 {

struct PixelBackendInfo {
  const char* name;
  const char* description;
  std::unique_ptr<PixelBackend> (*make)(const PixelBackendParams& params);
};

const std::vector<PixelBackendInfo>& pixel_backends();
// Null for an unknown name.
const PixelBackendInfo* find_pixel_backend(const std::string& name);
std::unique_ptr<PixelBackend> make_pixel_backend(const std::string& name,
                                                 const PixelBackendParams& params);

}  // namespace pp5
