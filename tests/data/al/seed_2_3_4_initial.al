{ Taylor's "first cut" hand-written program, section 2.3.4 (no force checks, no search).
  Source: seeds/000_1457622cbb9a2614.txt L1313-1330, as printed (no OCR slips). }

begin "pin in hole"
  { Declarations and initial affixments }

  { Grasp the pin }
  open bfingers to 1.0*inches;
  move blue to pin_grasp via pin_grasp_approach;
  center bfingers;
  affix pin to blue;

  { Extract, transport, and insert }
  move pin to in_hole_position via pin_withdraw, hole_approach;

  { Let go of the pin }
  open bfingers to 1.0*inches;
  unfix pin from blue;
  move blue to bpark via pin_grasp_approach;

end;
