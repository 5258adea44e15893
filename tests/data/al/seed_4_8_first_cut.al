{ A first-cut program in the style of section 2.3.4 (seeds/000_1457622cbb9a2614.txt L1313-1330)
  for fixture seed_4_8: grasp, one motion that extracts, transports and inserts, let go, park.
  No force checks, no search, no tap: it trusts the believed locations.
  The section's declarations and initial affixments (L1316, elided there) are written out with
  the numbers of the generated listing (L2723-2733): the same grasp (hand 3.54 cm up the pin,
  approach 5.08 cm further out), departure 6.79 cm above the rack, approach 2.54 cm above BH1,
  in-hole position d_f = 1.71 cm deep, turned 90 deg about the hole axis.
  As in L1318-1320, pin_grasp_approach is affixed to pin_grasp, which is affixed to the pin, so
  the final motion leaves along the hand's axis wherever the pin ended up. }

begin "pin in hole"
  frame pin_grasp, pin_grasp_approach, pin_withdraw, hole_approach, in_hole_position;

  { Declarations and initial affixments }
  affix pin_grasp to PIN1 at trans(rotn(vector(.924,.383,.001),180*deg),vector(0,0,3.54)*cm);
  affix pin_grasp_approach to pin_grasp at trans(nilrotn,vector(0,0,-5.08)*cm);
  pin_withdraw ← PIN1*trans(nilrotn,vector(0,0,6.79)*cm);
  hole_approach ← BH1*trans(rotn(zhat,90*deg),vector(0,0,2.54)*cm);
  in_hole_position ← BH1*trans(rotn(zhat,90*deg),vector(0,0,-1.71)*cm);

  { Grasp the pin }
  open bhand to 2.98*cm;
  move bmanip to pin_grasp via pin_grasp_approach;
  center bmanip;
  affix PIN1 to bmanip;

  { Extract, transport, and insert }
  move PIN1 to in_hole_position via pin_withdraw, hole_approach;

  { Let go of the pin }
  open bhand to 2.98*cm;
  unfix PIN1 from bmanip;
  move bmanip to bpark via pin_grasp_approach;
end;
