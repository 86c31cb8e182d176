#pragma once
// The "word" pixel backend: the instruction set executed a whole field at a time, every
// field a host integer per pixel, with loops over contiguous arrays of pixels that the
// compiler vectorises. It keeps no per-bit-cycle state (no carries, no bit-serial order), so
// it cannot be traced bit by bit; its pixel memory is bit-identical to "bit" after every
// instruction (tests/test_word_backend.cpp runs both in lockstep).
//
// Layout: pixel memory is ceil(memory_bits / 64) lanes of 64 bits per pixel, lane-major
// (lane k of every pixel in one contiguous array of pixels()). A field [lo, lo + width) lies
// in lane lo / 64 at bit lo % 64, or straddles two lanes; it is read with a shift and a mask
// and written with a masked merge under E. E is a list of spans (disjoint pixel ranges)
// outside which it is 0, and inside them one byte per pixel (0 or 1); the Enable stack holds
// both per level, the backing store lanes like pixel memory (allocated on first use). Every
// operation runs only over the spans (after a triangle's edge tests, its own columns of each
// of its rows), which is exact (E = 0 is never written) and makes its cost the pixels a
// primitive's bounding rows and edges leave; an edge test only narrows the spans, and so
// does a quadratic qtest (a sphere's outline) wherever its value cannot wrap: each row's
// part to the interval (or the two) where the condition holds, found by binary search on
// exact values, then to its first to last enabled pixel; any other test (cmp, qcmp, a
// quadratic qtest that could wrap, eq, ne) ANDs E pixel by pixel and narrows each row's part
// to its first to last enabled pixel. Saving or restoring E copies only the spans. E's bytes
// outside the spans are never read. A run of half-plane tests (a triangle's edges) is
// applied together when the next operation needs E, over only the rows of the band where
// all of them can hold (materialize()); so are E's bytes after eall, set only over what those
// tests leave. Likewise a run of qloads and movs of constants (a triangle's attributes) waits
// and is written in one walk (apply_loads). A field within one lane is read and written eight
// pixels at a time (word_backend.cpp: for_chunks), since a triangle's rows are a few pixels long.
//
// Contract: implements PixelBackend (firmware/isa/backend.hpp), including its one bit-serial
// corner: an ALU source field that overlaps its destination from below (src.lo < dst.lo)
// reads, at bit i, what the walk already wrote there; that case runs a per-pixel
// bit-serial emulation, every other one whole words.
#include <memory>
#include <vector>

#include "firmware/isa/backend.hpp"
#include "models/evaluator/linear_band.hpp"

namespace pp5 {

class WordBackend final : public PixelBackend {
 public:
  explicit WordBackend(const PixelBackendParams& params);

  const char* name() const override { return "word"; }
  const PixelArrayGeometry& geometry() const override { return geometry_; }
  void set_origin(int x0, int y0) override {
    materialize();
    x0_ = x0;
    y0_ = y0;
  }

  void enable_all() override;
  void push_enable() override;
  void pop_enable() override;
  void else_enable() override;

  void qtest(const QuadraticCoefficients& expr, Compare cond) override;
  void qload(const Field& dst, const QuadraticCoefficients& expr) override;
  void qcmp(const Field& field, const QuadraticCoefficients& expr, Compare cond) override;

  void mov(const Field& dst, const Source& src) override;
  void add(const Field& dst, const Source& src) override;
  void sub(const Field& dst, const Source& src) override;
  void logic(const Field& dst, const Source& src, Logic op) override;
  void invert(const Field& dst) override;
  void compare(const Field& a, const Source& b, Compare cond) override;
  void multiply(const Field& dst, const Field& a, const Field& b, bool window) override;
  void multiply_accumulate(const Field& dst, const Field& a, std::int64_t k) override;
  void store_to_backing(const Field& field, int block) override;
  void load_from_backing(const Field& field, int block) override;

  std::uint64_t read(int pixel, const Field& field) const override;
  void read_field(const Field& field, std::uint64_t* out) const override;
  void read_bytes(const Field* fields, int count, std::uint8_t* out) const override;
  void read_memory_planes(std::vector<std::uint64_t>& planes) const override;
  bool enabled(int pixel) const override;
  int count_enabled() const override;
  int enable_depth() const override { return stack_top_; }
  void write(int pixel, const Field& field, std::uint64_t value) override;

  std::unique_ptr<PixelBackend> clone() const override;
  bool same_state(const PixelBackend& other) const override;
  void copy_state_from(const PixelBackend& other) override;

 private:
  enum class Alu { mov, add, sub, and_, or_, xor_ };
  // Pixels [begin, end).
  struct Range {
    int begin = 0;
    int end = 0;
  };
  // After E was ANDed with something: it is still 0 outside spans_, which stay as they are.
  void enable_changed() {}
  // After an instruction that ANDed E with a test pixel by pixel (qcmp of a field across
  // two lanes, a quadratic qtest evaluated per pixel; cmp and qcmp within a lane do the same
  // row by row as they compare, with keep_enabled): each row's part of each span narrowed
  // to its first to last pixel with E = 1 (a row with none leaves the spans; a row enabled
  // to its end and the next from its start stay one span).
  // Exact, as E = 0 outside; what follows walks only what the test left: shade only the
  // pixels a primitive reached, the attributes only where a triangle is in front.
  void narrow_spans();
  // qtest of a linear expression whose value cannot wrap along a row: E cleared outside the
  // interval of each row where the condition holds, found by division, as the evaluator's
  // own fast path does, and spans_ narrowed to those intervals. False (nothing done) when
  // the expression is not such.
  bool qtest_linear(const QuadraticCoefficients& c, Compare cond);
  // qtest (lt, le, gt, ge) of any expression whose value cannot wrap on the spans: on each
  // row it is, modulo 2^result_bits, a quadratic (or linear) g(x) = a x^2 + b x + k of the
  // column with a, b, k reduced to result_bits, monotone on each side of its integer
  // arg-extremum, so the columns where the condition holds are one interval or the
  // complement of one, found by binary search on exact (128-bit) values; spans_ narrowed to
  // them (and to their first to last enabled pixel, or as they are while E's bytes wait to
  // be filled after eall: ones_), E's bytes untouched. False (nothing
  // done) when the condition is eq or ne or g leaves result_bits on some span's row part (at
  // its ends or its arg-extremum, the extremes of g over its integers): the value wraps
  // there, and the per-pixel evaluation decides. When the value cannot wrap anywhere in the
  // region and its form is definite (an ellipse's inside, a sphere's outline), only the band
  // of rows whose real extremum lies on the condition's side is searched (the rows where the
  // row's discriminant is >= 0, an interval); the others leave the spans.
  bool qtest_quadratic(const QuadraticCoefficients& c, Compare cond);
  // Pixels [from, to) with their E bytes as the test left them, appended to `kept` trimmed
  // to their first to last enabled pixel (nothing when none is), joined to the span before
  // when it ends where they begin.
  void keep_enabled(std::vector<Range>& kept, int from, int to) const;
  // The evaluator's column terms for `c` (row_a_, row_b_), before evaluate.
  void prepare_columns(const QuadraticCoefficients& c) const;
  // The field's values at pixels [r.begin, r.end) into out[p], extended to 64 bits by the
  // field's signedness (read_field's unsigned values when `extend` is false).
  void load(const std::uint64_t* lanes, const Field& f, Range r, std::uint64_t* out,
            bool extend) const;
  // out[p] into the field at pixels [r.begin, r.end), modulo 2^width, only where E = 1
  // (everywhere when `masked` is false).
  void store(std::uint64_t* lanes, const Field& f, Range r, const std::uint64_t* in, bool masked);
  // The expression's value at every pixel of r, wrapped to result_bits and sign-extended
  // (after prepare_columns(c)).
  void evaluate(const QuadraticCoefficients& c, Range r, std::uint64_t* out) const;
  // For each row of r: row_sink(index of the row's first pixel) gives a sink(x, value) that
  // takes, for each pixel x of the row in r, the expression's value (as evaluate) shifted
  // down by `shift` and cut to the field `as` (sign-extended when it is signed).
  template <class RowSink>
  void for_each_value(const QuadraticCoefficients& c, Range r, int shift, const Field& as,
                      RowSink row_sink) const;
  // f(y, row_start, from, to) for each row's part of each span in turn: pixels row_start +
  // [from, to) of row y. Rows are found by stepping from the span before (spans are in
  // order), not by a division per span: after a triangle's edge tests a span is one short
  // row, and the walk's cost per span is what the instructions below pay per row.
  template <class F>
  void for_each_span_row(F f) const;
  // qcmp's single pass over the spans for a field within one lane (and apply_loads' for
  // qload): the value (as for_each_value gives it, modulo 2^64 the same sum) computed per
  // pixel as ((A X + (D + B Y)) X + (C Y^2 + E Y + F), no column tables: a triangle's rows
  // are shorter than the region is wide), and compared with the field in place (then each
  // row's part narrowed as narrow_spans does, in the same walk). Only a square term
  // (kSquare: A != 0) and the field's signedness (kSigned) are compiled in; the condition
  // is applied without a branch per pixel.
  struct PixelValues;  // their per-pixel arithmetic (word_backend.cpp)
  template <bool kSquare, bool kSigned>
  void qcmp_lane(const Field& field, const QuadraticCoefficients& c, Compare cond);
  template <class ReadB>
  void compare_lane(const Field& a, Compare cond, ReadB read_b);
  // qload and qcmp's operand: bits [fraction_bits, fraction_bits + width) of the value.
  void expression_field(const QuadraticCoefficients& c, const Field& as, Range r,
                        std::uint64_t* out) const;
  void alu(const Field& dst, const Source& src, Alu op);
  // alu's path except for a source overlapping its destination from below: merge_lane with
  // the operation, chosen once per instruction (word_backend.cpp).
  void alu_merged(const Field& dst, const Source& src, Alu op);
  template <Alu kOp, class Read>
  void alu_merge(const Field& dst, Read source);
  template <class Read>
  void alu_merge_op(Alu op, const Field& dst, Read source);
  // value(old, base) merged into dst (within one lane or across two) under E over every
  // span, eight pixels at a time, in one pass (multiply's and multiply_accumulate's).
  template <class Value>
  void merge_lane(const Field& dst, Value value);
  // E &= (a cond b) over r; false when it found no pixel of r left enabled (true when it may
  // have: its general path does not look).
  bool compare_range(const Field& a, const Source& b, Compare cond, Range r);
  void alu_serial(const Field& dst, const Field& src, Alu op, Range r);
  // E &= (a cond b) over r, a and b extended values; wide when either is an unsigned 64-bit
  // field (a 65-bit comparison).
  void compare_values(const std::uint64_t* a, bool a_unsigned64, const std::uint64_t* b,
                      bool b_unsigned64, Compare cond, Range r);
  void check_field(const Field& f, const char* what) const;
  std::uint64_t* backing();

  PixelArrayGeometry geometry_;
  EvaluatorParams evaluator_;
  int fraction_bits_;
  int pixels_;
  int lanes_;  // 64-bit lanes of pixel memory per pixel
  int x0_ = 0;
  int y0_ = 0;
  // lanes_ x pixels_ (mutable: a read from a const backend writes the waiting qloads first)
  mutable std::vector<std::uint64_t> memory_;
  // pixels_, valid inside spans_ (mutable: materialize() fills it after eall)
  mutable std::vector<std::uint8_t> enable_;
  // pixels_ bytes per level the stack has reached (empty above), E's as of its push (copied
  // when E is next written: shared_level_); a pop swaps its level with E.
  // (mutable: own_enable makes a level's copy when a const read needs it)
  mutable std::vector<std::vector<std::uint8_t>> stack_;
  int stack_top_ = 0;
  // The level an epush saved whose bytes are still E's own (none written since), or -1: its
  // spans are saved, its bytes copied only when E's are about to be written (own_enable),
  // or not at all when a compare writes the new E into the level's buffer and swaps, or an
  // epop finds them unchanged. Every writer of E's bytes, and every reader of a level's,
  // calls own_enable first.
  mutable int shared_level_ = -1;
  void own_enable() const;
  // A stack level's bytes, allocated on first use.
  std::uint8_t* level_bytes(int level) const;
  std::vector<std::uint64_t> backing_;  // backing lanes x pixels_, allocated on first use
  // Disjoint pixel ranges, in order, outside which E is 0 (a superset of E's set pixels, at
  // most two ranges per row after a linear qtest, one from the first to the last enabled
  // pixel after a quadratic one): every operation walks only these. The same for each saved
  // level of the stack.
  // Lazily narrowed (materialize()): mutable so that reading E from a const backend applies
  // what is pending.
  mutable std::vector<Range> spans_;
  mutable std::vector<Range> spare_spans_;  // qtest's new spans are built here, then swapped in
  std::vector<std::vector<Range>> stack_spans_;
  // Linear half-plane tests (lt, le, gt, ge) not yet applied to spans_: consecutive ones (a
  // triangle's edge tests) are applied together, in one walk over only the rows where all of
  // them can hold, instead of one walk each over what the one before left. Every other
  // operation applies them first; the result is the same as applying them one by one
  // (models/evaluator/linear_band.hpp).
  static constexpr std::size_t kMaxPending = kMaxBandTests;
  mutable std::vector<LinearTest> pending_;
  // Set by eall: E's bytes within the spans are 1, whatever they hold. eall is followed by a
  // triangle's edge tests, so the bytes are filled (materialize()) only over what the tests
  // leave, not the whole array.
  mutable bool ones_ = false;
  // Writes that read no pixel memory, not yet done: qloads and movs of a constant, each to
  // a field within one lane (a triangle's attributes, seven qloads and a mov in a row in
  // phong.pp5; a sphere's depth and colour). A run of them is written in one walk over the
  // spans, which reads E and each lane it writes once per eight pixels, not once per
  // instruction; within a lane they are merged in their order, so a later one wins where two
  // overlap. E, the spans and the origin cannot change while they wait: every other
  // operation, and every read or write of pixel memory, writes them first (materialize(),
  // write_loads()).
  struct PendingLoad {
    Field dst;
    QuadraticCoefficients c;  // a mov's constant in F
    bool constant;            // a mov: c.F as it is, not the evaluator's value
  };
  void queue_load(const PendingLoad& load);
  static constexpr std::size_t kMaxLoads = 8;
  mutable std::vector<PendingLoad> loads_;
  void write_loads() const {
    if (!loads_.empty()) apply_loads();
  }
  void apply_loads() const;
  // Writes the waiting qloads, applies the pending tests, then fills E's bytes where ones_
  // says: every operation that reads or writes E or pixel memory calls it first.
  void materialize() const {
    write_loads();
    settle_enable();
  }
  // The pending tests and ones_ only (none is pending while qloads wait).
  void settle_enable() const;
  void apply_pending() const;
  // Scratch of pixels_ values each: operands, results, the evaluator's row tables (width
  // entries each). Not state: a new backend allocates it, on the thread that makes it (a
  // host thread's first allocations cost page faults in its own malloc arena); a copy
  // (clone, copy_state_from) starts without it, and it is allocated when the copy first
  // executes, so a kept state costs only its state.
  struct Scratch {
    std::vector<std::uint64_t> s0, s1, s2, row_a, row_b;
    Scratch() = default;
    Scratch(const Scratch&) {}
    Scratch& operator=(const Scratch&) { return *this; }
  };
  // The scratch, allocated on first use by a copy.
  Scratch& scratch() const {
    if (scratch_.s0.empty()) allocate_scratch();
    return scratch_;
  }
  void allocate_scratch() const;
  mutable Scratch scratch_;
};

}  // namespace pp5
