#pragma once
// The "bit" pixel backend: the instruction set executed bit-serially on the bit-sliced
// PixelArray, fed by the ExpressionEvaluator's bit-planes, as the hardware does it.
//
// Contract: implements PixelBackend (firmware/isa/backend.hpp). Each call is the one
// PixelArray / ExpressionEvaluator operation the instruction maps to, over the words where
// E has a set bit; a field operand becomes the field's planes, a constant a broadcast of the
// zero and ones planes, an expression the evaluator's planes of its integer bits (in scratch
// planes the backend owns). Beyond the interface, array() and evaluator() give the concrete
// models to code that is about them (their tests and benchmarks).
#include <memory>
#include <vector>

#include "firmware/isa/backend.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/pixel_array/pixel_array.hpp"

namespace pp5 {

class BitSlicedBackend final : public PixelBackend {
 public:
  explicit BitSlicedBackend(const PixelBackendParams& params);

  const char* name() const override { return "bit"; }
  const PixelArrayGeometry& geometry() const override { return array_.geometry(); }
  void set_origin(int x0, int y0) override { evaluator_.set_origin(x0, y0); }

  void enable_all() override { array_.enable_all(); }
  void push_enable() override { array_.push_enable(); }
  void pop_enable() override { array_.pop_enable(); }
  void else_enable() override { array_.else_enable(); }

  void qtest(const QuadraticCoefficients& expr, Compare cond) override;
  void qload(const Field& dst, const QuadraticCoefficients& expr) override;
  void qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) override;

  void mov(const Field& dst, const Source& src) override;
  void add(const Field& dst, const Source& src) override;
  void sub(const Field& dst, const Source& src) override;
  void logic(const Field& dst, const Source& src, Logic op) override;
  void invert(const Field& dst) override { array_.invert(dst); }
  void compare(const Field& a, const Source& b, Compare cond) override;
  void multiply(const Field& dst, const Field& a, const Field& b) override;
  void multiply_accumulate(const Field& dst, const Field& a, std::int64_t k) override;
  void store_to_backing(const Field& field, int block) override {
    array_.store_to_backing(field, block);
  }
  void load_from_backing(const Field& field, int block) override {
    array_.load_from_backing(field, block);
  }

  std::uint64_t read(int pixel, const Field& field) const override {
    return array_.read(pixel, field);
  }
  void read_field(const Field& field, std::uint64_t* out) const override;
  void read_memory_planes(std::vector<std::uint64_t>& planes) const override;
  bool enabled(int pixel) const override { return array_.enabled(pixel); }
  int count_enabled() const override { return array_.count_enabled(); }
  int enable_depth() const override { return array_.enable_depth(); }
  void write(int pixel, const Field& field, std::uint64_t value) override {
    array_.write(pixel, field, value);
  }

  std::unique_ptr<PixelBackend> clone() const override;
  bool same_state(const PixelBackend& other) const override;
  void copy_state_from(const PixelBackend& other) override;

  PixelArray& array() { return array_; }
  const PixelArray& array() const { return array_; }
  const ExpressionEvaluator& evaluator() const { return evaluator_; }

 private:
  Bits source_bits(const Source& src) const;
  // The integer bits [fraction_bits, fraction_bits + width) of an expression, as planes.
  Bits expression_bits(const QuadraticCoefficients& expr, const Field& as);

  PixelArray array_;
  ExpressionEvaluator evaluator_;
  int fraction_bits_;
  std::vector<Word> scratch_;  // Bits::kMaxBits planes: the evaluator's output
};

}  // namespace pp5
