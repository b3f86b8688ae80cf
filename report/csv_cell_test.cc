#include "report/csv_cell.h"

#include <gtest/gtest.h>

namespace bosfuse::report {
namespace {

TEST(CsvCell, PlainTextIsWrittenAsIs) {
  EXPECT_EQ(csv_text_cell("tc0 [degC]"), "tc0 [degC]");
  EXPECT_EQ(csv_text_cell(""), "");
  EXPECT_EQ(csv_text_cell("a-b=c"), "a-b=c");  // only the first character starts a formula
}

TEST(CsvCell, SeparatorsQuotesAndLineBreaksAreQuoted) {
  EXPECT_EQ(csv_text_cell("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_text_cell("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_text_cell("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_text_cell("cr\rhere"), "\"cr\rhere\"");
}

TEST(CsvCell, AFormulaIsNeutralised) {
  EXPECT_EQ(csv_text_cell("=cmd|' /C calc'!A0"), "\"'=cmd|' /C calc'!A0\"");
  EXPECT_EQ(csv_text_cell("+1+1"), "\"'+1+1\"");
  EXPECT_EQ(csv_text_cell("-2+3"), "\"'-2+3\"");
  EXPECT_EQ(csv_text_cell("@SUM(A1)"), "\"'@SUM(A1)\"");
  EXPECT_EQ(csv_text_cell("\t=1"), "\"'\t=1\"");
  EXPECT_EQ(csv_text_cell("\r=1"), "\"'\r=1\"");
  EXPECT_EQ(csv_text_cell("=HYPERLINK(\"http://x\",\"y\")"), "\"'=HYPERLINK(\"\"http://x\"\",\"\"y\"\")\"");
}

TEST(CsvCell, TheTextComesBackExactly) {
  for (const std::string text : {"=1+1", "'=1+1", "''", "'", "'plain", "plain", "-3.5", "@", "", "\t"}) {
    std::string value = csv_text_cell(text);
    if (value.size() >= 2 && value.front() == '"') value = value.substr(1, value.size() - 2);  // no "" inside these
    EXPECT_EQ(csv_text_from_cell(value), text) << text;
  }
}

}  // namespace
}  // namespace bosfuse::report
