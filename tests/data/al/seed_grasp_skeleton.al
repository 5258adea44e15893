{ Taylor's grasping skeleton with slots, section 3 (the code-skeleton discussion).
  Source: seeds/000_1457622cbb9a2614.txt L1777-1786.
  OCR slip fixed: L1779  object_grasp+trans(...) -> object_grasp*trans(...)  (frame * trans). }

open blue to initial_opening;
move blue to object_grasp
  via object_grasp*trans(nilrotN, vector(0,0,-4*inches));
center blue
  on opening < minimum_opening do
    begin
    stop;
    abort("It just isn't there!");
    end;
move object to object_pickup_point;
