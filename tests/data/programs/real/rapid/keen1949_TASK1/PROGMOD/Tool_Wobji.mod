MODULE Tool_Wobji
    PERS wobjdata wobj1{1,1}:=[[[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]]];
    TASK PERS wobjdata wobj2{1,1}:=[[[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]]];
    TASK PERS wobjdata wobj3{1,1}:=[[[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]]];
    TASK PERS wobjdata wobj4:=[FALSE,TRUE,"",[[348.502,-74.9611,102.32],[5.01292E-06,0.915147,-0.40312,4.27711E-06]],[[0,0,0],[1,0,0,0]]];
    TASK PERS wobjdata wobj5:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[344.96,-132.422,102.321],[6.06787E-06,0.915148,-0.403118,3.08981E-06]]];
ENDMODULE