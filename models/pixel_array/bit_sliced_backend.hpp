#pragma once
// The "bit" pixel backend: the instruction set executed bit-serially on the bit-sliced
// PixelArray, fed by the ExpressionEvaluator's bit-planes, as the hardware does it.
//
// Contract: implements PixelBackend (firmware/isa/backend.hpp). Each call is the one
// PixelArray / ExpressionEvaluator operation the instruction maps to, over the words where
// E has a set bit; a field operand becomes the field's planes, a constant a broadcast of the
// zero and ones planes, an expression the evaluator's planes of its integer bits (in scratch
// planes the backend owns). One exception to "each call is one operation": a run of linear
// half-plane qtests (a triangle's edges) is held back and applied together when anything
// else is asked of the backend, over only the rows where all of them can hold
// (models/evaluator/linear_band.hpp); E is then what the tests one by one would leave, and
// every accessor, including array(), sees it applied. An expression's planes stay in scratch
// while E only loses bits, so a qload of the expression a qcmp (or qload) has just evaluated, at
// the same width, takes them from there: they are the evaluator's planes for every word E still
// enables, exactly what evaluating again would give there. Beyond the interface, array() and
// evaluator() give the concrete models to code that is about them (their tests and benchmarks).
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "firmware/isa/backend.hpp"
#include "models/evaluator/evaluator.hpp"
#include "models/evaluator/linear_band.hpp"
#include "models/pixel_array/pixel_array.hpp"

namespace pp5 {

class BitSlicedBackend final : public PixelBackend {
 public:
  explicit BitSlicedBackend(const PixelBackendParams& params);

  const char* name() const override { return "bit"; }
  const PixelArrayGeometry& geometry() const override { return array_.geometry(); }
  void set_origin(int x0, int y0) override {
    settle();
    held_.valid = false;
    evaluator_.set_origin(x0, y0);
  }

  void enable_all() override {
    pending_count_ = 0;  // E becomes all 1: no test held back matters
    held_.valid = false;
    array_.enable_all();
  }
  void push_enable() override {
    settle();
    array_.push_enable();
  }
  void pop_enable() override {
    settle();
    held_.valid = false;
    array_.pop_enable();
  }
  void else_enable() override {
    settle();
    held_.valid = false;
    array_.else_enable();
  }

  void qtest(const QuadraticCoefficients& expr, Compare cond) override;
  void qload(const Field& dst, const QuadraticCoefficients& expr) override;
  void qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) override;

  void mov(const Field& dst, const Source& src) override;
  void add(const Field& dst, const Source& src) override;
  void sub(const Field& dst, const Source& src) override;
  void logic(const Field& dst, const Source& src, Logic op) override;
  void invert(const Field& dst) override {
    settle();
    array_.invert(dst);
  }
  void compare(const Field& a, const Source& b, Compare cond) override;
  void multiply(const Field& dst, const Field& a, const Field& b, bool window) override;
  void multiply_accumulate(const Field& dst, const Field& a, std::int64_t k) override;
  // Backing-store transfers and scalar reads and writes of memory ignore E: what is held
  // back stays held back.
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
  bool enabled(int pixel) const override {
    settle();
    return array_.enabled(pixel);
  }
  int count_enabled() const override {
    settle();
    return array_.count_enabled();
  }
  int enable_depth() const override { return array_.enable_depth(); }
  void write(int pixel, const Field& field, std::uint64_t value) override {
    array_.write(pixel, field, value);
  }

  std::unique_ptr<PixelBackend> clone() const override;
  bool same_state(const PixelBackend& other) const override;
  void copy_state_from(const PixelBackend& other) override;

  PixelArray& array() {
    settle();
    held_.valid = false;  // the caller may change E
    return array_;
  }
  const PixelArray& array() const {
    settle();
    return array_;
  }
  const ExpressionEvaluator& evaluator() const { return evaluator_; }

 private:
  Bits source_bits(const Source& src) const;
  // The integer bits [fraction_bits, fraction_bits + width) of an expression, as planes.
  Bits expression_bits(const QuadraticCoefficients& expr, const Field& as);
  // E &= (expr <cond> 0), over the words where E has a set bit.
  void and_test(const QuadraticCoefficients& expr, Compare cond);

  // The linear tests held back (qtest): applied by settle(), which every operation that
  // reads or writes E calls first. Logically const: E is the same before and after, only
  // how it is held changes.
  void settle() const {
    if (pending_count_ != 0) const_cast<BitSlicedBackend*>(this)->apply_pending();
  }
  void apply_pending();

  PixelArray array_;
  std::array<LinearTest, kMaxBandTests> pending_{};
  std::size_t pending_count_ = 0;
  ExpressionEvaluator evaluator_;
  int fraction_bits_;
  std::vector<Word> scratch_;  // Bits::kMaxBits planes: the evaluator's output
  // What scratch_ holds when valid: the planes of `expr` for a field of `width` bits, at every
  // word where E has a set bit. Cleared by whatever overwrites scratch_, moves the origin or may
  // set a bit of E (enable_all, pop_enable, else_enable, copy_state_from, array()).
  struct HeldPlanes {
    bool valid = false;
    QuadraticCoefficients expr;
    int width = 0;
  };
  HeldPlanes held_;
};

}  // namespace pp5
