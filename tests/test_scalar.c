/* sim/scalar: the strict reader of numbers and words every input goes
 * through. Table-driven: each text with the verdict and value expected, for
 * whole numbers, decimal numbers (double and float), sizes' digit runs and
 * words; the messages' phrases; and err_escape, which keeps a message that
 * quotes such text on one line. */
#include "sim/scalar.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "sim/err.h"
#include "testing.h"

static const char *why_name(enum scalar_why w) {
  static const char *const names[] = {"OK",           "EMPTY",  "SPACE",    "CONTROL",
                                      "LEADING_ZERO", "SYNTAX", "OVERFLOW", "UNDERFLOW"};
  return (unsigned)w < sizeof names / sizeof names[0] ? names[w] : "?";
}

static void test_u64(void) {
  static const struct {
    const char *text;
    enum scalar_why want;
    uint64_t value;
  } cases[] = {
      {"0", SCALAR_OK, 0},
      {"7", SCALAR_OK, 7},
      {"10", SCALAR_OK, 10},
      {"4096", SCALAR_OK, 4096},
      {"18446744073709551615", SCALAR_OK, UINT64_MAX},
      {"18446744073709551616", SCALAR_OVERFLOW, 0},
      {"99999999999999999999999", SCALAR_OVERFLOW, 0},
      /* One rule for leading zeros: 010 is neither 8 nor 10. */
      {"010", SCALAR_LEADING_ZERO, 0},
      {"00", SCALAR_LEADING_ZERO, 0},
      {"08", SCALAR_LEADING_ZERO, 0},
      {"0000000000000000000000001", SCALAR_LEADING_ZERO, 0},
      {"", SCALAR_EMPTY, 0},
      {" 4", SCALAR_SPACE, 0},
      {"4 ", SCALAR_SPACE, 0},
      {"\n4", SCALAR_SPACE, 0},
      {"4\n", SCALAR_SPACE, 0},
      {"\t4", SCALAR_SPACE, 0},
      {"4\r", SCALAR_SPACE, 0},
      {" ", SCALAR_SPACE, 0},
      {"4 4", SCALAR_SYNTAX, 0},
      {"0x10", SCALAR_SYNTAX, 0},
      {"0X10", SCALAR_SYNTAX, 0},
      {"+4", SCALAR_SYNTAX, 0},
      {"-1", SCALAR_SYNTAX, 0},
      {"-0", SCALAR_SYNTAX, 0},
      {"1e3", SCALAR_SYNTAX, 0},
      {"4.0", SCALAR_SYNTAX, 0},
      {"4KiB", SCALAR_SYNTAX, 0},
      {"four", SCALAR_SYNTAX, 0},
      {"\xd9\xa4", SCALAR_SYNTAX, 0}, /* ARABIC-INDIC DIGIT FOUR */
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    uint64_t v = 12345;
    enum scalar_why w = scalar_u64(cases[i].text, &v);
    EXPECTF(w == cases[i].want, "u64 '%s': got %s, want %s", cases[i].text, why_name(w),
            why_name(cases[i].want));
    if (cases[i].want == SCALAR_OK)
      EXPECTF(v == cases[i].value, "u64 '%s': got %llu", cases[i].text, (unsigned long long)v);
    else EXPECTF(v == 12345, "u64 '%s': the output was written on failure", cases[i].text);
  }
  /* The first n bytes only (a size's digits before its unit). */
  uint64_t v = 0;
  EXPECT(scalar_u64_n("512KiB", 3, &v) == SCALAR_OK && v == 512);
  EXPECT(scalar_u64_n("010KiB", 3, &v) == SCALAR_LEADING_ZERO);
  EXPECT(scalar_u64_n("KiB", 0, &v) == SCALAR_EMPTY);
  EXPECT(scalar_u64_n("0KiB", 1, &v) == SCALAR_OK && v == 0);
}

static void test_f64(void) {
  static const struct {
    const char *text;
    enum scalar_why want;
    double value;
  } cases[] = {
      {"0", SCALAR_OK, 0},
      {"1.5", SCALAR_OK, 1.5},
      {"-1.5", SCALAR_OK, -1.5},
      {"+1.5", SCALAR_OK, 1.5},
      {"0.25", SCALAR_OK, 0.25},
      {"-0.25", SCALAR_OK, -0.25},
      {".5", SCALAR_OK, 0.5},
      {"5.", SCALAR_OK, 5},
      {"10", SCALAR_OK, 10},
      {"1e3", SCALAR_OK, 1000},
      {"1E-3", SCALAR_OK, 1e-3},
      {"1e+03", SCALAR_OK, 1000}, /* an exponent's zeros are printf's own habit */
      {"2.5e-05", SCALAR_OK, 2.5e-5},
      {"0e7", SCALAR_OK, 0},
      {"-0", SCALAR_OK, 0},
      {"0.000", SCALAR_OK, 0},
      {"1e-310", SCALAR_OK, 1e-310}, /* a subnormal: rounded, not refused */
      {"1.7976931348623157e308", SCALAR_OK, DBL_MAX},
      {"1e309", SCALAR_OVERFLOW, 0},
      {"-1e999", SCALAR_OVERFLOW, 0},
      {"1e-400", SCALAR_UNDERFLOW, 0},
      {"0e-400", SCALAR_OK, 0},
      /* The sweep value: a newline before the number. */
      {"\n1.5", SCALAR_SPACE, 0},
      {"1.5\n", SCALAR_SPACE, 0},
      {" 1.5", SCALAR_SPACE, 0},
      {"1.5 ", SCALAR_SPACE, 0},
      {"", SCALAR_EMPTY, 0},
      {"010", SCALAR_LEADING_ZERO, 0},
      {"01.5", SCALAR_LEADING_ZERO, 0},
      {"-01.5", SCALAR_LEADING_ZERO, 0},
      {"00", SCALAR_LEADING_ZERO, 0},
      {"00.5", SCALAR_LEADING_ZERO, 0},
      {".", SCALAR_SYNTAX, 0},
      {"-", SCALAR_SYNTAX, 0},
      {"+-1", SCALAR_SYNTAX, 0},
      {"1e", SCALAR_SYNTAX, 0},
      {"1e+", SCALAR_SYNTAX, 0},
      {"e3", SCALAR_SYNTAX, 0},
      {"1.5.2", SCALAR_SYNTAX, 0},
      {"1,5", SCALAR_SYNTAX, 0},
      {"0x1p3", SCALAR_SYNTAX, 0},
      {"0x10", SCALAR_SYNTAX, 0},
      {"inf", SCALAR_SYNTAX, 0},
      {"-inf", SCALAR_SYNTAX, 0},
      {"nan", SCALAR_SYNTAX, 0},
      {"infinity", SCALAR_SYNTAX, 0},
      {"1.5x", SCALAR_SYNTAX, 0},
      {"1 5", SCALAR_SYNTAX, 0},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    double v = 12345;
    enum scalar_why w = scalar_f64(cases[i].text, &v);
    EXPECTF(w == cases[i].want, "f64 '%s': got %s, want %s", cases[i].text, why_name(w),
            why_name(cases[i].want));
    if (cases[i].want == SCALAR_OK)
      EXPECTF(v == cases[i].value, "f64 '%s': got %.17g", cases[i].text, v);
    else EXPECTF(v == 12345, "f64 '%s': the output was written on failure", cases[i].text);
  }
  double z = 1;
  EXPECT(scalar_f64("-0", &z) == SCALAR_OK && z == 0 && signbit(z));

  /* float: strtof's rounding (no double rounding through a double), the
   * float's own range. */
  float f = 0;
  EXPECT(scalar_f32("0.1", &f) == SCALAR_OK && f == 0.1f);
  EXPECT(scalar_f32("3.40282347e38", &f) == SCALAR_OK && f == FLT_MAX);
  EXPECT(scalar_f32("1e39", &f) == SCALAR_OVERFLOW);
  EXPECT(scalar_f32("1.40129846e-45", &f) == SCALAR_OK && f == 0x1p-149f);
  EXPECT(scalar_f32("1e-50", &f) == SCALAR_UNDERFLOW);
  EXPECT(scalar_f32(" 1", &f) == SCALAR_SPACE);
  EXPECT(scalar_f32("01", &f) == SCALAR_LEADING_ZERO);
  EXPECT(scalar_f32("inf", &f) == SCALAR_SYNTAX);
  /* A decimal halfway between two floats that a double lands beside: strtof
   * rounds the decimal once, (float)strtod would round twice. */
  EXPECT(scalar_f32("1.00000005960464477550", &f) == SCALAR_OK && f == 0x1.000002p0f);
}

static void test_text(void) {
  static const struct {
    const char *text;
    enum scalar_why want;
  } cases[] = {
      {"room.yaml", SCALAR_OK},
      {"../scenes/my room.yaml", SCALAR_OK}, /* spaces inside are a name's own */
      {"x", SCALAR_OK},
      {"\xc3\xa9t\xc3\xa9", SCALAR_OK}, /* UTF-8 */
      {"", SCALAR_EMPTY},
      {" room.yaml", SCALAR_SPACE},
      {"room.yaml ", SCALAR_SPACE},
      {"\nroom.yaml", SCALAR_SPACE},
      {"room\n.yaml", SCALAR_CONTROL},
      {"room\t.yaml", SCALAR_CONTROL},
      {"room\x1b[31m", SCALAR_CONTROL},
      {"room\x7f", SCALAR_CONTROL},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    enum scalar_why w = scalar_text(cases[i].text);
    EXPECTF(w == cases[i].want, "text case %zu: got %s, want %s", i, why_name(w),
            why_name(cases[i].want));
  }
  /* Every verdict but OK and SYNTAX has a phrase for the message. */
  for (int w = SCALAR_OK; w <= SCALAR_UNDERFLOW; w++) {
    const char *t = scalar_why_text((enum scalar_why)w);
    EXPECTF(t && (w == SCALAR_OK || w == SCALAR_SYNTAX ? !t[0] : t[0] != '\0'), "%s: '%s'",
            why_name((enum scalar_why)w), t ? t : "(null)");
  }
}

static void test_escape(void) {
  char buf[64];
  err_escape(buf, sizeof buf, "got '\n1.5'\t\r\x01\x7f!");
  EXPECTF(!strcmp(buf, "got '\\n1.5'\\t\\r\\x01\\x7f!"), "%s", buf);
  /* Cut short whole: never half an escape. */
  err_escape(buf, 6, "ab\ncd");
  EXPECTF(!strcmp(buf, "ab\\nc"), "%s", buf);
  err_escape(buf, 4, "ab\ncd");
  EXPECTF(!strcmp(buf, "ab"), "%s", buf);
  /* err_set makes the message and the file name one line each. */
  struct err e;
  memset(&e, 0, sizeof e);
  err_set(&e, "a\nb.yaml", 2, 3, "k: not a number (got '%s')", "\n1.5");
  EXPECTF(!strcmp(e.msg, "k: not a number (got '\\n1.5')"), "%s", e.msg);
  EXPECTF(!strcmp(e.file, "a\\nb.yaml"), "%s", e.file);
}

int main(void) {
  test_u64();
  test_f64();
  test_text();
  test_escape();
  return testing_done("test_scalar");
}
