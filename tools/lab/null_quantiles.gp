# SPDX-License-Identifier: Apache-2.0
# Quantile plot of the model-gap candidates' significance on clean runs (GAP.md section 7):
#   swivel-bench-model-gap --set validation --null-quantiles null_z.dat
#   gnuplot -e "data='null_z.dat'; out='null_quantiles.png'" tools/lab/null_quantiles.gp
# Under the null every single-effect candidate's z is a standard normal deviate: the points
# should follow the diagonal; a candidate is named from z = 5.
if (!exists("data")) data = 'null_z.dat'
if (!exists("out")) out = 'null_quantiles.png'
set terminal pngcairo size 900,600 font ",11"
set output out
set title "Single-effect candidates on clean validation runs: observed z against the normal"
set xlabel "expected standard normal quantile"
set ylabel "observed z (sorted)"
set key top left
set grid
set xrange [-4:4.5]
set yrange [-1:*]
plot x title "calibrated (y = x)" with lines lc rgb "gray" dt 2, \
     5 title "named from z = 5" with lines lc rgb "red" dt 3, \
     data index 0 using 1:2 title "sensor to pose" with points pt 7 ps 0.5 lc rgb "#1f77b4", \
     data index 1 using 1:2 title "command to motion" with points pt 7 ps 0.5 lc rgb "#ff7f0e"
