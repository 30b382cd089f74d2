# A merged table's quoted values hold commas (rays: "primary,shadow,diffuse"):
# print each line with the quotes dropped and those commas as +, so that
# awk -F, reads one column a value. Used by summary.sh and plot.sh.
{
  o = ""; q = 0
  for (i = 1; i <= length($0); i++) {
    ch = substr($0, i, 1)
    if (ch == "\"") { q = !q; continue }
    o = o ((ch == "," && q) ? "+" : ch)
  }
  print o
}
